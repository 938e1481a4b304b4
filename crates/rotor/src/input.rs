//! Reading the text files a user hands the tool (model, study, campaign files, speed
//! tables) with bounds: only regular files, and no more than a size limit, checked before
//! anything is read, so that a device (`/dev/zero`), a FIFO or a huge file is refused with
//! its size and the limit instead of filling memory or hanging.

use std::io::Read;
use std::path::Path;

/// The largest input text file: 16 MiB. The built-in model is 30 kB and a generated
/// network's table a few hundred kB; sixteen megabytes leave room for tabulated supports
/// and long speed tables.
pub const MAX_INPUT_BYTES: u64 = 16 << 20;

/// Reads the regular file `path` as UTF-8 text of at most `limit` bytes. Errors (of kind
/// `InvalidInput` for the refusals) say what the path is or how large it is.
pub fn read_text(path: &Path, limit: u64) -> std::io::Result<String> {
    let meta = std::fs::metadata(path)?;
    if !meta.is_file() {
        let kind = if meta.is_dir() {
            "a directory"
        } else {
            "not a regular file (a device, FIFO or socket)"
        };
        return Err(std::io::Error::new(
            std::io::ErrorKind::InvalidInput,
            format!("it is {kind}; give a file"),
        ));
    }
    if meta.len() > limit {
        return Err(std::io::Error::new(
            std::io::ErrorKind::InvalidInput,
            format!(
                "it is {} bytes, above the limit of {} bytes for an input file",
                meta.len(),
                limit
            ),
        ));
    }
    let mut bytes = Vec::new();
    // (bounded again while reading: the file may grow after the check)
    std::fs::File::open(path)?
        .take(limit + 1)
        .read_to_end(&mut bytes)?;
    if bytes.len() as u64 > limit {
        return Err(std::io::Error::new(
            std::io::ErrorKind::InvalidInput,
            format!("it grew above the limit of {limit} bytes while being read"),
        ));
    }
    String::from_utf8(bytes).map_err(|e| {
        std::io::Error::new(
            std::io::ErrorKind::InvalidData,
            not_utf8(e.as_bytes(), e.utf8_error().valid_up_to()),
        )
    })
}

/// Where text stops being UTF-8: line, column and byte offset of the first bad byte.
fn not_utf8(bytes: &[u8], at: usize) -> String {
    let before = &bytes[..at];
    let line = before.iter().filter(|&&b| b == b'\n').count() + 1;
    let line_start = before
        .iter()
        .rposition(|&b| b == b'\n')
        .map_or(0, |i| i + 1);
    // the column in characters of the valid text before it on its line
    let column = String::from_utf8_lossy(&before[line_start..])
        .chars()
        .count()
        + 1;
    format!(
        "line {line}, column {column} (byte {at}, 0x{:02x}): not UTF-8 text; save the file \
         as UTF-8",
        bytes[at]
    )
}

/// The command-line flag that sets each study setting (`tmrotor sweep`), for messages:
/// a value refused names the key a study file writes and the flag a user typed.
pub const SETTING_FLAGS: &[(&str, &str)] = &[
    ("flow_l_min", "--flow"),
    ("cooling_temp_c", "--cooling-temp"),
    ("ambient_temp_c", "--ambient-temp"),
    ("order", "--order"),
    ("omega_start", "--omega"),
    ("omega_end", "--omega"),
    ("ds_max", "--ds-max"),
    ("max_points", "--max-points"),
    ("sip_intervals", "--sip-intervals"),
    ("reduction_cutoff_rad_s", "--reduction-cutoff"),
    ("verify_orders", "--verify-orders"),
];

/// ` (flag --x)` for a setting that a flag sets, else nothing.
pub fn flag_note(field: &str) -> String {
    SETTING_FLAGS
        .iter()
        .find(|(k, _)| *k == field)
        .map_or(String::new(), |(_, f)| format!(" (flag {f})"))
}

/// Creates the output directory `dir` (with its parents) for figures, tables or recordings. A path
/// that exists but is not a directory (a file, `/dev/full`) is named as such, where
/// `create_dir_all` says only "File exists".
pub fn ensure_dir(dir: &Path) -> std::io::Result<()> {
    if dir.exists() && !dir.is_dir() {
        return Err(std::io::Error::new(
            std::io::ErrorKind::AlreadyExists,
            "it exists and is not a directory (the output is a directory of files)",
        ));
    }
    std::fs::create_dir_all(dir)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn text_that_is_not_utf8_is_refused_with_its_position() {
        let dir = tempfile::tempdir().expect("tempdir");
        let path = dir.path().join("m.toml");
        std::fs::write(&path, b"a = 1\nname = \"\xc3\xa9x\xff\"\n").expect("write");
        let err = read_text(&path, MAX_INPUT_BYTES).expect_err("not UTF-8");
        let msg = err.to_string();
        assert!(msg.contains("line 2, column 11 (byte 17, 0xff)"), "{msg}");
        std::fs::write(&path, "a = \"é\"\n").expect("write");
        assert_eq!(
            read_text(&path, MAX_INPUT_BYTES).expect("UTF-8"),
            "a = \"é\"\n"
        );
    }
}
