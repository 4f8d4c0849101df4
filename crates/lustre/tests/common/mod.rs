//! Running the lustre binary in the command-line tests: its output in words, and the two
//! outcomes a test expects.

use std::process::{Command, Output};

/// The binary under test, without backtraces (a user's error prints none).
pub fn lustre() -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_lustre"));
    c.env("RUST_BACKTRACE", "0");
    c
}

/// Standard output and error together.
pub fn text(o: &Output) -> String {
    format!(
        "{}{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    )
}

/// Runs `c`, which must succeed; its output.
pub fn ok(c: &mut Command) -> String {
    let o = c.output().expect("runs");
    let t = text(&o);
    assert!(o.status.success(), "{c:?}: {t}");
    t
}

/// Runs `c`, which must fail with a message, not a panic or an allocation abort; its output.
pub fn fails(c: &mut Command) -> String {
    let o = c.output().expect("runs");
    let t = text(&o);
    assert!(!o.status.success(), "{c:?} should fail: {t}");
    assert!(
        !t.contains("panicked") && !t.contains("memory allocation"),
        "{t}"
    );
    t
}
