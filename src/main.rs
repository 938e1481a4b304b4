//! The `tmrotor` command: parses the command line and hands it to [`tmrotor::cli::run`];
//! the exit codes are mapped in one place, [`tmrotor::cli::exit_code`] (see
//! `docs/user-guide.md`).

use clap::Parser;

/// mimalloc keeps freed memory for reuse: the Newton solves allocate and drop matrices of a
/// few MB at every iteration, which the system allocator maps and unmaps each time (measured
/// on the default sweep without stability: 27 % of the wall time in page faults).
#[global_allocator]
static GLOBAL: mimalloc::MiMalloc = mimalloc::MiMalloc;

fn main() -> std::process::ExitCode {
    tmrotor::keep_freed_memory();
    tmrotor::sequential_dense_kernels();
    let cli = tmrotor::cli::Cli::parse();
    tmrotor::cli::exit_code("tmrotor", tmrotor::cli::run(cli))
}
