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
    let mut text = String::new();
    // (bounded again while reading: the file may grow after the check)
    std::fs::File::open(path)?
        .take(limit + 1)
        .read_to_string(&mut text)?;
    if text.len() as u64 > limit {
        return Err(std::io::Error::new(
            std::io::ErrorKind::InvalidInput,
            format!("it grew above the limit of {limit} bytes while being read"),
        ));
    }
    Ok(text)
}
