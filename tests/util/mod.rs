//! Shared by the end-to-end tests: run the real binary in a given folder.

use std::path::Path;
use std::process::{Command, Output};

/// Run `eulerdisk ARGS…` with `dir` as the working folder.
pub fn eulerdisk(dir: &Path, args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_eulerdisk"))
        .args(args)
        .current_dir(dir)
        .output()
        .expect("run eulerdisk")
}
