//! The `bdmorph` command line.

mod cli;

use std::process::ExitCode;

use clap::{CommandFactory, FromArgMatches};

/// Every (sub)command with negative numbers allowed as values (`--frames -1`, `--t -0.5`):
/// they reach the option's own check rather than being taken for flags.
fn allow_negative_numbers(command: clap::Command) -> clap::Command {
    command
        .allow_negative_numbers(true)
        .mut_subcommands(allow_negative_numbers)
}

fn main() -> ExitCode {
    let parsed = allow_negative_numbers(cli::Cli::command())
        .try_get_matches()
        .and_then(|matches| cli::Cli::from_arg_matches(&matches));
    let args = match parsed {
        Ok(args) => args,
        Err(e) => {
            use clap::error::ErrorKind;
            if matches!(
                e.kind(),
                ErrorKind::DisplayHelp
                    | ErrorKind::DisplayVersion
                    | ErrorKind::DisplayHelpOnMissingArgumentOrSubcommand
            ) {
                e.exit();
            }
            // One line, like every other error; `--help` has the details.
            eprintln!("bdmorph: error: {} (see --help)", one_line(&e.to_string()));
            return ExitCode::from(2);
        }
    };
    match cli::run(args) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!(
                "bdmorph: error: {}",
                bdmorph::Spelling::CLI.respell(&e.to_string())
            );
            ExitCode::FAILURE
        }
    }
}

/// The first line of a clap error, without its `error: ` prefix. When that line ends with a
/// colon ("the following required arguments were not provided:"), the indented lines that
/// follow it (the arguments) are joined to it.
fn one_line(text: &str) -> String {
    let mut lines = text.lines();
    let first = lines.next().unwrap_or("invalid arguments");
    let mut out = first.strip_prefix("error: ").unwrap_or(first).to_owned();
    if out.ends_with(':') {
        let items: Vec<&str> = lines
            .take_while(|l| l.starts_with(' '))
            .map(str::trim)
            .collect();
        if !items.is_empty() {
            out.push(' ');
            out.push_str(&items.join(", "));
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::one_line;

    #[test]
    fn clap_errors_become_one_line() {
        assert_eq!(
            one_line("error: unexpected argument 'x' found\n\nUsage: bdmorph\n"),
            "unexpected argument 'x' found"
        );
        assert_eq!(
            one_line(
                "error: the following required arguments were not provided:\n  --output <PROGRAM>\n  <SOURCE>\n\nUsage: bdmorph compile\n"
            ),
            "the following required arguments were not provided: --output <PROGRAM>, <SOURCE>"
        );
    }
}
