use clap::Parser;

fn main() -> std::process::ExitCode {
    let cli = tmrotor::cli::Cli::parse();
    match tmrotor::cli::run(cli) {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(err) => {
            eprintln!("error: {err:#}");
            std::process::ExitCode::from(1)
        }
    }
}
