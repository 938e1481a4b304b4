//! `replay`: inspect and re-derive tmrotor recordings; see `tmrotor::record::replay`.

fn main() -> std::process::ExitCode {
    tmrotor::record::replay::main()
}
