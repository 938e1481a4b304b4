//! Safe outputs: one writer per recording or campaign directory (an OS file lock), and
//! recordings written under a temporary name beside their target and renamed into place
//! when the run ends.
//!
//! * `<target>.lock` is locked (`flock`, released by the OS when the process dies) while a
//!   recording is written, and holds the writer's process id and start time; a second
//!   writer stops at once with [`RecordError::Locked`], which names the lock and its holder.
//!   A campaign locks `campaign.lock` in its output directory the same way.
//! * `<target>.partial` is the recording while the run goes on (readable by `replay`
//!   meanwhile). When the run ends (completed, interrupted or failed) it is synced and
//!   renamed to `<target>`, atomically replacing an earlier recording there, but only when it
//!   holds at least one point or there is no earlier recording: a run that fails before its
//!   first point leaves an existing recording untouched.
//! * A `.partial` left by a killed process (its lock is free) is never overwritten: the next
//!   writer moves it to `<stem>.killed-<unix time>.mcap` and says so.

use std::fs::{File, OpenOptions};
use std::io::{Read, Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};

use super::RecordError;

/// `<path>` with `suffix` appended to its file name.
fn with_suffix(path: &Path, suffix: &str) -> PathBuf {
    let mut name = path
        .file_name()
        .map(|n| n.to_os_string())
        .unwrap_or_default();
    name.push(suffix);
    path.with_file_name(name)
}

/// Where the recording for `target` is written while its run goes on.
pub fn partial_path(target: &Path) -> PathBuf {
    with_suffix(target, ".partial")
}

/// Writes `bytes` to `path` under its [`partial_path`] and renames it into place, so a file
/// at `path` is always whole.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> std::io::Result<()> {
    let tmp = partial_path(path);
    std::fs::write(&tmp, bytes)?;
    std::fs::rename(&tmp, path)
}

/// Refuses an output path that is not a regular file or absent (a directory, a device, a
/// FIFO, a socket), or that is one of the command's `inputs` (a model, study or campaign
/// file, a recording being read): the recording is renamed over its target when the run
/// ends, which would destroy what is there. Call before any computing.
pub fn check_target(target: &Path, inputs: &[&Path]) -> Result<(), RecordError> {
    let refuse = |reason: String| {
        Err(RecordError::Target {
            path: target.to_path_buf(),
            reason,
        })
    };
    if target.as_os_str().is_empty() {
        return refuse("the path is empty".into());
    }
    match std::fs::symlink_metadata(target) {
        Ok(meta) => {
            let kind = meta.file_type();
            if kind.is_dir() {
                return refuse("it is a directory; give a file name inside it".into());
            }
            if kind.is_symlink() {
                return refuse("it is a symbolic link; give the file it points to".into());
            }
            if !kind.is_file() {
                return refuse(
                    "it is not a regular file (a device, FIFO or socket); the recording would replace it"
                        .into(),
                );
            }
        }
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {}
        Err(e) => return refuse(format!("cannot inspect it: {e}")),
    }
    let same = |a: &Path, b: &Path| match (a.canonicalize(), b.canonicalize()) {
        (Ok(a), Ok(b)) => a == b,
        _ => false,
    };
    for input in inputs {
        if same(target, input) {
            return refuse(format!(
                "it is an input of this command ({}); write the output elsewhere",
                input.display()
            ));
        }
    }
    Ok(())
}

/// The lock file of a recording `target`.
pub fn lock_path(target: &Path) -> PathBuf {
    with_suffix(target, ".lock")
}

/// A held writer lock; released (and its file removed) when dropped.
#[derive(Debug)]
pub struct WriterLock {
    file: Option<File>,
    path: PathBuf,
}

impl WriterLock {
    /// The lock file.
    pub fn path(&self) -> &Path {
        &self.path
    }
}

impl Drop for WriterLock {
    fn drop(&mut self) {
        // remove the file while still holding the lock, then release it
        let _ = std::fs::remove_file(&self.path);
        if let Some(f) = self.file.take() {
            let _ = f.unlock();
        }
    }
}

/// Locks the file `lock` for `what` (a recording, a campaign), without waiting: a lock held
/// by another process is an error naming the lock file and its holder.
pub fn lock(lock: &Path, what: &str) -> Result<WriterLock, RecordError> {
    let mut file = OpenOptions::new()
        .read(true)
        .write(true)
        .create(true)
        .truncate(false)
        .open(lock)
        .map_err(|source| RecordError::Create {
            path: lock.to_path_buf(),
            source,
        })?;
    match file.try_lock() {
        Ok(()) => {}
        Err(std::fs::TryLockError::WouldBlock) => {
            let mut holder = String::new();
            let _ = file.read_to_string(&mut holder);
            let holder = holder.trim();
            return Err(RecordError::Locked {
                what: what.to_string(),
                lock: lock.to_path_buf(),
                holder: if holder.is_empty() {
                    "another process".into()
                } else {
                    holder.to_string()
                },
            });
        }
        Err(std::fs::TryLockError::Error(source)) => {
            return Err(RecordError::Create {
                path: lock.to_path_buf(),
                source,
            });
        }
    }
    let since = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map(|d| d.as_secs())
        .unwrap_or(0);
    let text = format!(
        "tmrotor process {} (writing since unix time {since})\n",
        std::process::id()
    );
    let written = file
        .set_len(0)
        .and_then(|()| file.seek(SeekFrom::Start(0)))
        .and_then(|_| file.write_all(text.as_bytes()))
        .and_then(|()| file.flush());
    written.map_err(|source| RecordError::Create {
        path: lock.to_path_buf(),
        source,
    })?;
    Ok(WriterLock {
        file: Some(file),
        path: lock.to_path_buf(),
    })
}

/// Moves a `.partial` left by a killed writer out of the way (never overwritten): to
/// `<stem>.killed-<unix time>.mcap` beside it. Returns the new name, if there was one.
pub fn keep_stale_partial(target: &Path) -> Result<Option<PathBuf>, RecordError> {
    let partial = partial_path(target);
    if !partial.exists() {
        return Ok(None);
    }
    let stem = target
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "recording".into());
    let secs = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map(|d| d.as_secs())
        .unwrap_or(0);
    let kept = target.with_file_name(format!("{stem}.killed-{secs}.mcap"));
    std::fs::rename(&partial, &kept).map_err(|source| RecordError::Create {
        path: partial.clone(),
        source,
    })?;
    Ok(Some(kept))
}

/// Ends the write of `target`: the synced `.partial` replaces `target` when it holds a
/// point or `target` does not exist; otherwise it is removed and `target` kept. Returns
/// whether the new recording is now at `target`.
pub fn commit(target: &Path, has_points: bool) -> Result<bool, RecordError> {
    let partial = partial_path(target);
    if has_points || !target.exists() {
        std::fs::rename(&partial, target).map_err(|source| RecordError::Create {
            path: target.to_path_buf(),
            source,
        })?;
        // the rename itself is durable once the directory is synced
        if let Some(dir) = target.parent().filter(|d| !d.as_os_str().is_empty())
            && let Ok(d) = File::open(dir)
        {
            let _ = d.sync_all();
        }
        Ok(true)
    } else {
        let _ = std::fs::remove_file(&partial);
        Ok(false)
    }
}
