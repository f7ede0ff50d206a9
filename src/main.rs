use clap::Parser;
use std::process::ExitCode;

fn main() -> ExitCode {
    let cli = match rayreel::cli::Cli::try_parse() {
        Ok(cli) => cli,
        Err(e) => return usage(&e),
    };
    match rayreel::commands::run(cli) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            let code = e.exit_code();
            // A stderr that cannot be written loses the message, not the exit code.
            let line = rayreel::console::error_line(&e.to_string(), code);
            rayreel::console::stderr_line(format_args!("{line}"));
            ExitCode::from(code)
        }
    }
}

/// Help and version go to stdout (exit 0); a bad command line is reported in the one style of
/// every error, `rayreel: …`, with clap's hint, and exits 2.
fn usage(e: &clap::Error) -> ExitCode {
    if !e.use_stderr() {
        let _ = e.print();
        return ExitCode::SUCCESS;
    }
    let text = e.render().to_string();
    let text = text.strip_prefix("error: ").unwrap_or(&text);
    rayreel::console::stderr_write(&format!(
        "rayreel: {}",
        rayreel::console::printable_lines(text)
    ));
    ExitCode::from(2)
}
