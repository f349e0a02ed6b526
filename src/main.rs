//! The `surfmotion` binary: parse arguments, call the library, map errors to
//! exit codes (0 ok, 1 bad input or command line, 2 internal error). A panic is caught and
//! reported as an internal error, so exit code 101 cannot happen.

mod cli;

use std::process::ExitCode;

fn main() -> ExitCode {
    // Silence the default panic message; we print our own.
    std::panic::set_hook(Box::new(|info| {
        let loc = info
            .location()
            .map(|l| format!(" at {}:{}", l.file(), l.line()))
            .unwrap_or_default();
        say(&format!("surfmotion: internal error{loc}: {info}"));
    }));
    match std::panic::catch_unwind(cli::main) {
        Ok(Ok(())) => ExitCode::SUCCESS,
        Ok(Err(e)) if e.is::<cli::OutputClosed>() => ExitCode::SUCCESS,
        Ok(Err(e)) if e.is::<cli::Usage>() => ExitCode::from(1),
        Ok(Err(e)) => {
            say(&format!("surfmotion: {}", cli::one_line(&e)));
            ExitCode::from(1)
        }
        Err(_) => {
            say("surfmotion: this is a bug; please report it with the command line and input file");
            ExitCode::from(2)
        }
    }
}

/// A line on stderr. A closed stderr is ignored: `eprintln!` panics
/// there, and in the panic hook that aborted the process (`surfmotion
/// play --help 2>&1 | head -1` exited 134).
fn say(line: &str) {
    use std::io::Write;
    let _ = writeln!(std::io::stderr(), "{line}");
}
