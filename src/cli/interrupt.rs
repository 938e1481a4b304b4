//! Ctrl-C for long runs: the first interrupt sets a flag that the sweep, campaign and
//! transient drivers poll between steps (they stop there and close their recordings with
//! the status "interrupted"); a second one exits at once.

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, OnceLock};

static INTERRUPT: OnceLock<Arc<AtomicBool>> = OnceLock::new();

/// Installs (once per process) a Ctrl-C handler that sets the returned flag instead of
/// killing the process. A driver polls it (`flag.load(Ordering::Relaxed)`) between
/// points, stops, and finishes its sink as interrupted. A second Ctrl-C while the flag is
/// already set exits the process at once (status 130).
pub fn install_interrupt_flag() -> Result<Arc<AtomicBool>, ctrlc::Error> {
    if let Some(flag) = INTERRUPT.get() {
        return Ok(flag.clone());
    }
    let flag = Arc::new(AtomicBool::new(false));
    let handler_flag = flag.clone();
    ctrlc::set_handler(move || {
        if handler_flag.swap(true, Ordering::SeqCst) {
            // deliberate: a second interrupt stops at once, without waiting for the step
            eprintln!(
                "\nsecond interrupt: stopping at once; every point already written stays in \
                 the in-progress recording (OUT.partial, without its closing status; replay \
                 reads it, and the next sweep to the same output moves it aside)"
            );
            std::process::exit(130);
        }
    })?;
    Ok(INTERRUPT.get_or_init(|| flag).clone())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn interrupt_flag_is_installed_once_and_shared() {
        let a = install_interrupt_flag().expect("handler");
        let b = install_interrupt_flag().expect("same handler");
        assert!(Arc::ptr_eq(&a, &b));
        assert!(!a.load(Ordering::Relaxed));
    }
}
