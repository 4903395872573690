//! How a run ends when it fails: one sentence on stderr and an exit status that says whose
//! the fault is.
//!
//! - 2, bad input: anything about what the user gave — a flag, a parameter, a scene or
//!   mesh file, a file that cannot be read, a size or count over a limit, an output that
//!   the checks before any work refuse (wrong extension, existing file without `--force`,
//!   missing folder, dangling link, a folder that is not a report). The command line's own
//!   refusals are [`BadInput`]; the library's errors are mapped by kind ([`library_code`]).
//! - 1, internal failure: everything else — an output that cannot be written once the
//!   checks have passed (a full disk, a size limit, a folder made unwritable meanwhile), a
//!   caught panic, a broken invariant. An error the command line does not recognise is
//!   counted here, not as input, so a failure is never blamed on the user by default.
//!
//! Standard output and error follow the conventions of command-line tools
//! ([`set_signals`]): a closed pipe ends the run quietly by SIGPIPE (the shell's status
//! 141, as for `cat`), a write that fails otherwise (a full disk) is one sentence and
//! status 1, and a file-size limit (`ulimit -f`) is a failed write (status 1) instead of a
//! SIGXFSZ that kills the run with its output half written.

use std::fmt::Display;
use std::sync::Mutex;

/// Exit status for bad input.
pub const BAD_INPUT: u8 = 2;
/// Exit status for every other failure.
pub const INTERNAL: u8 = 1;

/// An input error found by the command line itself (exit status 2).
#[derive(Debug)]
pub struct BadInput(pub String);

impl Display for BadInput {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for BadInput {}

/// A [`BadInput`] error with `msg`.
pub fn bad_input(msg: impl Into<String>) -> anyhow::Error {
    BadInput(msg.into()).into()
}

/// Marks an error about the user's input as bad input, its sentence kept:
/// `"{context}: {error}"`.
pub trait InputContext<T> {
    /// The error, after `context`, as a [`BadInput`].
    fn input_context<C: Display>(self, context: impl FnOnce() -> C) -> anyhow::Result<T>;
}

impl<T, E: Display> InputContext<T> for Result<T, E> {
    fn input_context<C: Display>(self, context: impl FnOnce() -> C) -> anyhow::Result<T> {
        self.map_err(|e| bad_input(format!("{}: {e}", context())))
    }
}

/// The exit status of a library error, by its kind ([`shadowlab::Error::is_bad_input`]).
pub fn library_code(e: &shadowlab::Error) -> u8 {
    if e.is_bad_input() {
        BAD_INPUT
    } else {
        INTERNAL
    }
}

/// The exit status of a failed command: the first cause in the chain (outermost first)
/// that says whose fault it is, else [`INTERNAL`].
pub fn exit_code(e: &anyhow::Error) -> u8 {
    for cause in e.chain() {
        if let Some(se) = cause.downcast_ref::<shadowlab::Error>() {
            return library_code(se);
        }
        if cause.is::<BadInput>() {
            return BAD_INPUT;
        }
    }
    INTERNAL
}

/// The sentence of a failed command: the chain joined, outermost context first.
pub fn sentence(e: &anyhow::Error) -> String {
    let parts: Vec<String> = e.chain().map(|c| c.to_string()).collect();
    parts.join(": ")
}

/// Signal dispositions for a command-line tool, set before anything is written: SIGPIPE
/// back to its default (Rust ignores it, turning a closed pipe into a write error on every
/// later `println!`), so a reader that stops reading ends the run quietly; SIGXFSZ
/// ignored, so a write past the file-size limit fails with `EFBIG`, which is reported
/// and leaves no partial file, rather than killing the run.
pub fn set_signals() {
    // SAFETY: setting the disposition of two signals to default or ignore installs no
    // handler code; nothing else runs yet.
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
        libc::signal(libc::SIGXFSZ, libc::SIG_IGN);
    }
}

/// Writes one line to stderr, ignoring a failure (there is nowhere left to report it).
pub fn say(line: &str) {
    use std::io::Write;
    let _ = writeln!(std::io::stderr(), "{line}");
}

/// The prefix of the panic `println!` and `eprintln!` raise when a write fails.
const PRINT_FAILED: &str = "failed printing to std";

/// The sentence for a failed write to standard output or error (a panic message of
/// `println!`), or `None` for any other panic.
fn print_failure(msg: &str) -> Option<String> {
    let rest = msg.strip_prefix(PRINT_FAILED)?;
    let (stream, why) = rest.split_once(": ").unwrap_or((rest, "unknown error"));
    let why = why.split(" (os error").next().unwrap_or(why);
    Some(format!("cannot write to std{stream} ({why})"))
}

/// What the panic hook saw of the last panic: its message and where it was raised.
/// `(true, sentence)` for a failed write to standard output or error, which is no bug.
static LAST_PANIC: Mutex<Option<(bool, String)>> = Mutex::new(None);

/// Runs `f`, turning a panic (on this thread or one of its workers, which rayon passes
/// on) into an internal failure whose sentence names the message and where it was raised,
/// instead of a backtrace.
pub fn catch_panics<T>(f: impl FnOnce() -> anyhow::Result<T>) -> anyhow::Result<T> {
    if let Ok(mut last) = LAST_PANIC.lock() {
        *last = None;
    }
    std::panic::set_hook(Box::new(|info| {
        let msg = if let Some(s) = info.payload().downcast_ref::<&str>() {
            s.to_string()
        } else if let Some(s) = info.payload().downcast_ref::<String>() {
            s.clone()
        } else {
            "panic".to_string()
        };
        let place = info
            .location()
            .map(|l| format!(" at {}:{}", l.file(), l.line()))
            .unwrap_or_default();
        if let Ok(mut last) = LAST_PANIC.lock() {
            last.get_or_insert(match print_failure(&msg) {
                Some(sentence) => (true, sentence),
                None => (false, format!("{msg}{place}")),
            });
        }
    }));
    let outcome = std::panic::catch_unwind(std::panic::AssertUnwindSafe(f));
    let _ = std::panic::take_hook();
    outcome.unwrap_or_else(|_| {
        let what = LAST_PANIC.lock().ok().and_then(|mut l| l.take());
        match what {
            Some((true, sentence)) => Err(anyhow::anyhow!(sentence)),
            Some((false, what)) => Err(anyhow::anyhow!(
                "internal failure (a bug in shadowlab, not your input): {what}"
            )),
            None => Err(anyhow::anyhow!(
                "internal failure (a bug in shadowlab, not your input): panic"
            )),
        }
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::PathBuf;

    #[test]
    fn library_errors_map_by_kind() {
        use shadowlab::Error;
        let input = [
            Error::io("a.obj", "does not exist"),
            Error::format("a.obj", "line 3: bad face"),
            Error::Scene {
                scene: "s".into(),
                what: "is empty".into(),
            },
            Error::param("sm.resolution = 0 is outside 16..=16384"),
            Error::Limit("too many triangles".into()),
        ];
        for e in input {
            let shown = e.to_string();
            assert_eq!(exit_code(&e.into()), BAD_INPUT, "{shown}");
        }
        let output = Error::Output {
            path: PathBuf::from("out.png"),
            what: "File too large".into(),
        };
        assert_eq!(exit_code(&output.into()), INTERNAL);
        let internal = Error::Internal("a node lost its parent".into());
        assert_eq!(exit_code(&internal.into()), INTERNAL);
    }

    #[test]
    fn the_first_cause_that_knows_decides() {
        let e = anyhow::Error::from(shadowlab::Error::param("bad")).context("technique sm");
        assert_eq!(exit_code(&e), BAD_INPUT);
        assert_eq!(sentence(&e), "technique sm: bad");
        let e = bad_input("--frames 0 is outside 1..=100000");
        assert_eq!(exit_code(&e), BAD_INPUT);
        let e: anyhow::Result<f32> = "x".parse::<f32>().input_context(|| "--camera fov");
        let e = e.unwrap_err();
        assert_eq!(exit_code(&e), BAD_INPUT);
        assert_eq!(sentence(&e), "--camera fov: invalid float literal");
    }

    #[test]
    fn unrecognised_errors_are_internal() {
        let io = std::io::Error::new(std::io::ErrorKind::PermissionDenied, "denied");
        let e = anyhow::Error::from(io).context("cannot create report/frames");
        assert_eq!(exit_code(&e), INTERNAL);
        assert_eq!(exit_code(&anyhow::anyhow!("an invariant broke")), INTERNAL);
    }

    #[test]
    fn panics_become_internal_failures() {
        let r: anyhow::Result<()> = catch_panics(|| panic!("the tree lost a node"));
        let e = r.unwrap_err();
        assert_eq!(exit_code(&e), INTERNAL);
        let s = sentence(&e);
        assert!(s.contains("the tree lost a node"), "{s}");
        assert!(s.contains("failure.rs"), "{s}");
        // A panic on a worker thread reaches the caller too.
        let r: anyhow::Result<()> = catch_panics(|| {
            let n = std::thread::scope(|s| s.spawn(|| -> usize { panic!("worker 7") }).join())
                .unwrap_or_else(|p| std::panic::resume_unwind(p));
            Ok(n)
        })
        .map(|_: usize| ());
        assert!(sentence(&r.unwrap_err()).contains("worker 7"));
        // A failed print is a failed write, not a bug.
        let r: anyhow::Result<()> = catch_panics(|| {
            panic!("failed printing to stdout: No space left on device (os error 28)")
        });
        let e = r.unwrap_err();
        assert_eq!(exit_code(&e), INTERNAL);
        assert_eq!(
            sentence(&e),
            "cannot write to stdout (No space left on device)"
        );
        // No panic: the result as it is.
        assert_eq!(catch_panics(|| Ok(3)).unwrap(), 3);
    }
}
