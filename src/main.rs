use clap::Parser;
use std::process::ExitCode;

fn main() -> ExitCode {
    let cli = rayreel::cli::Cli::parse();
    match rayreel::run(cli) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("rayreel: {}", rayreel::console::printable(&e.to_string()));
            ExitCode::from(e.exit_code())
        }
    }
}
