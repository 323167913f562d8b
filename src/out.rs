//! Standard output for every command that prints: a reader that goes away (`photonmap info
//! scene.toml | head -1`) ends the program quietly with the shell's code for a death by SIGPIPE
//! (141), as every Unix tool does, instead of panicking in `println!`.

use std::io::{ErrorKind, Write};

/// Writes one line to stdout; on a closed pipe exits at once with 141, on any other write
/// error says so on stderr and exits with 1.
pub fn line(args: std::fmt::Arguments<'_>) {
    let mut out = std::io::stdout().lock();
    if let Err(e) = out.write_fmt(args).and_then(|()| out.write_all(b"\n")).and_then(|()| out.flush()) {
        if e.kind() == ErrorKind::BrokenPipe {
            std::process::exit(141);
        }
        eprintln!("photonmap: error: standard output: {e}");
        std::process::exit(1);
    }
}

/// `println!` through [`line`].
macro_rules! outln {
    () => { $crate::out::line(format_args!("")) };
    ($($arg:tt)*) => { $crate::out::line(format_args!($($arg)*)) };
}
pub(crate) use outln;
