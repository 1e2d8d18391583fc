//! Shared by the integration tests: the fixtures and their analyses, run the real
//! binary in a given folder, read JSON.

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use std::sync::{Mutex, OnceLock};

use eulerdisk::analyse::{Experiment, analyse_clip};
use eulerdisk::config::ExperimentConfig;
use serde_json::Value;

/// `fixtures/NAME` of the repository (`scripts/make-fixtures`).
pub fn fixture(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("fixtures")
        .join(name)
}

/// The ground truth of a rendered fixture, `fixtures/NAME` (`….truth.json`).
pub fn truth(name: &str) -> Value {
    json(&fixture(name))
}

/// `analyse_clip` of the fixture NAME with the config TEXT (as `test.toml`), run
/// once for the test binary: several tests read the same analysis, which is the
/// same every time (`determinism`).
pub fn analysed(name: &str, text: &str) -> &'static Experiment {
    type Analyses = HashMap<(String, String), &'static OnceLock<Experiment>>;
    static ANALYSES: OnceLock<Mutex<Analyses>> = OnceLock::new();
    let once = *ANALYSES
        .get_or_init(Default::default)
        .lock()
        .unwrap()
        .entry((name.to_owned(), text.to_owned()))
        .or_insert_with(|| Box::leak(Box::default()));
    // Two tests asking at once: one analyses, the other waits for it.
    once.get_or_init(|| {
        let config = ExperimentConfig::parse(text, Path::new("test.toml")).unwrap();
        analyse_clip(&fixture(name), &config, &|_, _| {}).unwrap()
    })
}

/// The JSON file at `path`.
pub fn json(path: &Path) -> Value {
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

/// A number of a JSON document.
pub fn f(v: &Value) -> f64 {
    v.as_f64().unwrap()
}

/// Run `eulerdisk ARGS…` with `dir` as the working folder.
pub fn eulerdisk(dir: &Path, args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_eulerdisk"))
        .args(args)
        .current_dir(dir)
        .output()
        .expect("run eulerdisk")
}
