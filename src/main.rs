use clap::Parser;
use std::process::ExitCode;

fn main() -> ExitCode {
    let cli = rayreel::cli::Cli::parse();
    match rayreel::run(cli) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("rayreel: {e}");
            ExitCode::from(e.exit_code())
        }
    }
}
