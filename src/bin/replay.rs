//! `replay`: inspect and re-derive tmrotor recordings; see `tmrotor::cli::replay`.

/// The allocator of `tmrotor` (see there): `replay stability` and `replay orbit` run the
/// same solvers.
#[global_allocator]
static GLOBAL: mimalloc::MiMalloc = mimalloc::MiMalloc;

fn main() -> std::process::ExitCode {
    tmrotor::keep_freed_memory();
    tmrotor::sequential_dense_kernels();
    tmrotor::cli::replay::main()
}
