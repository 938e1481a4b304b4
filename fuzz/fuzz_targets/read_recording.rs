//! Any bytes given to the recording reader: it must return (a recording or an error)
//! without panicking, hanging or allocating beyond the input's size, and what it calls
//! complete must hold no damage notes.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    if let Ok(rec) = tmrotor::record::reader::read_recording_bytes(data, "fuzz.mcap".as_ref()) {
        if rec.complete {
            assert!(rec.missing.is_empty());
            assert!(rec.notes.iter().all(|n| !n.starts_with("damaged")));
        }
    }
});
