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
