//! Results on stdout, with every write checked: a reader that stops early
//! (`pcaline eval | head`) ends the command quietly, and any other failure
//! (a full disk, `> /dev/full`) is an error that names stdout, never a
//! panic.

use crate::exit::stdout_error;
use std::io::Write;

/// Writes `args` to stdout ([`crate::exit::StdoutClosed`] for a broken pipe).
pub fn write_stdout(args: std::fmt::Arguments<'_>) -> anyhow::Result<()> {
    let mut out = std::io::stdout().lock();
    out.write_fmt(args).and_then(|()| out.flush()).map_err(stdout_error)
}

/// `println!` that returns the write's error instead of panicking.
macro_rules! outln {
    () => {
        $crate::out::write_stdout(format_args!("\n"))
    };
    ($($arg:tt)*) => {
        $crate::out::write_stdout(format_args!("{}\n", format_args!($($arg)*)))
    };
}

/// `print!` that returns the write's error instead of panicking.
macro_rules! out {
    ($($arg:tt)*) => {
        $crate::out::write_stdout(format_args!($($arg)*))
    };
}

pub(crate) use {out, outln};
