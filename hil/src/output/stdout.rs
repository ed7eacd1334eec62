//! Standard output that a reader closing the pipe ends quietly: `hil beliefs … | head` stops
//! when `head` has its lines, where `print!` would panic on the broken pipe.

use std::io::{ErrorKind, Write};

/// Writes `text` to standard output and flushes it. A reader that has gone (a broken pipe) is
/// not an error: the rest is not wanted. Any other failure is returned.
pub fn print(text: &str) -> std::io::Result<()> {
    let mut out = std::io::stdout().lock();
    match out.write_all(text.as_bytes()).and_then(|()| out.flush()) {
        Err(e) if e.kind() == ErrorKind::BrokenPipe => Ok(()),
        r => r,
    }
}

/// [`print`]s a command's report: success, or exit status 2 with the failure on standard
/// error, named after `command` (`hil beliefs`, `hil echoes`).
pub fn print_report(command: &str, text: &str) -> std::process::ExitCode {
    match print(text) {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("{command}: standard output: {e}");
            std::process::ExitCode::from(2)
        }
    }
}
