//! Helpers shared by the binary's end-to-end tests: run `demcon`, a scratch folder, the output.
#![allow(dead_code)]

use std::path::PathBuf;
use std::process::{Command, Output};

/// Runs the `demcon` binary with `args`.
pub fn demcon(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_demcon"))
        .args(args)
        .output()
        .expect("run demcon")
}

/// A new empty folder for one test (`tag` keeps the test files apart).
pub fn scratch(tag: &str, name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("demcon-{tag}-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// Standard output then standard error, as text.
pub fn text(o: &Output) -> String {
    format!(
        "{}{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    )
}
