//! The reference pages stay true to the code: `docs/cli.md` against the built
//! binary's `--help`, and `docs/config.md` against the config parser.
//!
//! CLI: for every subcommand `eulerdisk --help` lists, `eulerdisk SUB --help` is run
//! and every long flag it prints must have a row in the section `## \`eulerdisk SUB\``
//! of `docs/cli.md`; every flag that section lists must exist (`--help` and
//! `--version` aside). Config: every key documented in `docs/config.md`, set to its
//! documented example value, must be accepted by `ExperimentConfig::parse` (whose
//! structs reject unknown keys, so a misspelt or stale row fails); every key of a
//! fully populated `ExperimentConfig`, and every key of the TOML examples in
//! `README.md`, `docs/` and `src/config.rs`'s module docs, must be documented.
//! Helpers are inline so that the file can become a module of one test binary.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};
use std::process::Command;

use eulerdisk::config::{
    CalibrationConfig, DiskConfig, ExperimentConfig, FitConfig, HaltChoice, Plate, RimZeroChoice,
    VisionConfig,
};
use eulerdisk::model::params::Preset;

/// The repository root (where `Cargo.toml` is).
fn docs_repo_root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn docs_read(relative: &str) -> String {
    let path = docs_repo_root().join(relative);
    std::fs::read_to_string(&path)
        .unwrap_or_else(|e| panic!("{}: cannot be read: {e}", path.display()))
}

/// `eulerdisk ARGS…` run from the built binary; its standard output.
fn docs_help(args: &[&str]) -> String {
    let out = Command::new(env!("CARGO_BIN_EXE_eulerdisk"))
        .args(args)
        .output()
        .unwrap_or_else(|e| panic!("eulerdisk {}: cannot run: {e}", args.join(" ")));
    assert!(
        out.status.success(),
        "eulerdisk {} exited with {}: {}",
        args.join(" "),
        out.status,
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8(out.stdout).expect("help text is UTF-8")
}

/// Every `--long-flag` token in `text` (letters, digits and `-` after the two dashes).
fn docs_long_flags(text: &str) -> BTreeSet<String> {
    let mut flags = BTreeSet::new();
    let chars: Vec<char> = text.chars().collect();
    let mut i = 0;
    while i + 2 < chars.len() {
        let starts_token = i == 0 || !(chars[i - 1].is_alphanumeric() || chars[i - 1] == '-');
        if starts_token
            && chars[i] == '-'
            && chars[i + 1] == '-'
            && chars[i + 2].is_ascii_alphanumeric()
        {
            let mut j = i + 2;
            while j < chars.len() && (chars[j].is_ascii_alphanumeric() || chars[j] == '-') {
                j += 1;
            }
            flags.insert(
                chars[i..j]
                    .iter()
                    .collect::<String>()
                    .trim_end_matches('-')
                    .to_string(),
            );
            i = j;
        } else {
            i += 1;
        }
    }
    flags
}

/// The subcommands `eulerdisk --help` lists under "Commands:" (`help` aside).
fn docs_subcommands(help: &str) -> Vec<String> {
    let mut in_commands = false;
    let mut subs = Vec::new();
    for line in help.lines() {
        if line.starts_with("Commands:") {
            in_commands = true;
            continue;
        }
        if in_commands {
            if !line.starts_with(' ') {
                break;
            }
            // A command's line is indented by two; its wrapped help further.
            if line.starts_with("  ") && !line.starts_with("   ") {
                let name = line.split_whitespace().next().unwrap_or_default();
                if !name.is_empty() && name != "help" {
                    subs.push(name.to_string());
                }
            }
        }
    }
    subs
}

/// The long flags of a subcommand's `--help`: the first `--flag` of each option line
/// under "Options:" (indented by at most six spaces; wrapped help text is indented
/// further and may name other flags).
fn docs_help_flags(help: &str) -> BTreeSet<String> {
    let mut in_options = false;
    let mut flags = BTreeSet::new();
    for line in help.lines() {
        if line.starts_with("Options:") {
            in_options = true;
            continue;
        }
        if !in_options {
            continue;
        }
        if !line.is_empty() && !line.starts_with(' ') {
            break;
        }
        let indent = line.len() - line.trim_start().len();
        if indent <= 6 && line.trim_start().starts_with('-') {
            let head = line.trim_start().split("  ").next().unwrap_or_default();
            if let Some(flag) = docs_long_flags(head).into_iter().next() {
                flags.insert(flag);
            }
        }
    }
    flags
}

/// The cells of a Markdown table row, trimmed (`None` for a line that is not a row).
fn docs_cells(line: &str) -> Option<Vec<String>> {
    let line = line.trim();
    if !line.starts_with('|') {
        return None;
    }
    // `\|` inside a cell is an escaped bar, not a column break.
    let masked = line.replace("\\|", "\u{0}");
    let inner = masked.trim_start_matches('|').trim_end_matches('|');
    Some(
        inner
            .split('|')
            .map(|c| c.replace('\u{0}', "|").trim().to_string())
            .collect(),
    )
}

/// `docs/cli.md`: for each section `## \`eulerdisk SUB\``, the long flags in the first
/// column of its tables.
fn docs_cli_sections(text: &str) -> BTreeMap<String, BTreeSet<String>> {
    let mut sections: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
    let mut current: Option<String> = None;
    for line in text.lines() {
        if let Some(title) = line.strip_prefix("## ") {
            current = title
                .trim()
                .trim_matches('`')
                .strip_prefix("eulerdisk ")
                .map(|s| s.trim().to_string());
            if let Some(sub) = &current {
                sections.entry(sub.clone()).or_default();
            }
            continue;
        }
        let (Some(sub), Some(cells)) = (&current, docs_cells(line)) else {
            continue;
        };
        if let Some(first) = cells.first() {
            sections
                .get_mut(sub)
                .expect("section entered")
                .extend(docs_long_flags(first));
        }
    }
    sections
}

#[test]
fn every_cli_flag_is_documented_and_every_documented_flag_exists() {
    let doc_file = "docs/cli.md";
    let documented = docs_cli_sections(&docs_read(doc_file));
    let subs = docs_subcommands(&docs_help(&["--help"]));
    assert!(
        subs.len() >= 5,
        "eulerdisk --help listed only {subs:?}: the help parser no longer reads it"
    );
    let ignored: BTreeSet<&str> = ["--help", "--version"].into();
    let mut problems = Vec::new();
    for sub in &subs {
        let Some(in_docs) = documented.get(sub) else {
            problems.push(format!(
                "{doc_file}: no section `## \\`eulerdisk {sub}\\`` for subcommand `{sub}`"
            ));
            continue;
        };
        let in_help: BTreeSet<String> = docs_help_flags(&docs_help(&[sub, "--help"]))
            .into_iter()
            .filter(|f| !ignored.contains(f.as_str()))
            .collect();
        for flag in in_help.difference(in_docs) {
            problems.push(format!(
                "{doc_file}: `eulerdisk {sub} --help` lists `{flag}`, which the section `eulerdisk {sub}` does not document"
            ));
        }
        for flag in in_docs.difference(&in_help) {
            if !ignored.contains(flag.as_str()) {
                problems.push(format!(
                    "{doc_file}: the section `eulerdisk {sub}` documents `{flag}`, which `eulerdisk {sub} --help` does not list"
                ));
            }
        }
    }
    for sub in documented.keys() {
        if !subs.contains(sub) {
            problems.push(format!(
                "{doc_file}: section `eulerdisk {sub}` documents a subcommand that `eulerdisk --help` does not list"
            ));
        }
    }
    assert!(problems.is_empty(), "{}", problems.join("\n"));
}

/// One documented config key: its table (`""` for the top level), its name, and the
/// example value in TOML syntax.
#[derive(Debug, Clone)]
struct DocKey {
    table: String,
    key: String,
    example: String,
}

impl DocKey {
    fn dotted(&self) -> String {
        if self.table.is_empty() {
            self.key.clone()
        } else {
            format!("{}.{}", self.table, self.key)
        }
    }
}

/// `docs/config.md`: the rows of the tables under `## Top level` and `## \`[table]\``,
/// key in backticks in the first column and the TOML example in the "example" column.
fn docs_config_keys(text: &str) -> Vec<DocKey> {
    let mut keys = Vec::new();
    let mut table: Option<String> = None;
    let mut example_column: Option<usize> = None;
    for line in text.lines() {
        if let Some(title) = line.strip_prefix("## ") {
            let title = title.trim();
            table = if title.eq_ignore_ascii_case("top level") {
                Some(String::new())
            } else {
                title
                    .trim_matches('`')
                    .strip_prefix('[')
                    .and_then(|t| t.strip_suffix(']'))
                    .map(str::to_string)
            };
            example_column = None;
            continue;
        }
        let (Some(table), Some(cells)) = (&table, docs_cells(line)) else {
            continue;
        };
        if cells.first().is_some_and(|c| c == "key") {
            example_column = cells.iter().position(|c| c == "example");
            continue;
        }
        let first = &cells[0];
        let Some(key) = first.strip_prefix('`').and_then(|k| k.strip_suffix('`')) else {
            continue;
        };
        if !key.chars().all(|c| c.is_ascii_alphanumeric() || c == '_') {
            continue;
        }
        let column = example_column.unwrap_or_else(|| {
            panic!("docs/config.md: the table holding `{key}` has no \"example\" column")
        });
        let example = cells
            .get(column)
            .map(|c| c.trim_matches('`').to_string())
            .unwrap_or_default();
        keys.push(DocKey {
            table: table.clone(),
            key: key.to_string(),
            example,
        });
    }
    keys
}

/// A TOML text setting `keys` (all in one table).
fn docs_toml(keys: &[&DocKey]) -> String {
    let mut text = String::new();
    if let Some(first) = keys.first()
        && !first.table.is_empty()
    {
        text += &format!("[{}]\n", first.table);
    }
    for k in keys {
        text += &format!("{} = {}\n", k.key, k.example);
    }
    text
}

/// Every dotted key path of a TOML table (tables recursed into, arrays are values).
fn docs_toml_paths(table: &toml::Table, prefix: &str, out: &mut BTreeSet<String>) {
    for (key, value) in table {
        let path = if prefix.is_empty() {
            key.clone()
        } else {
            format!("{prefix}.{key}")
        };
        match value {
            toml::Value::Table(inner) => docs_toml_paths(inner, &path, out),
            _ => {
                out.insert(path);
            }
        }
    }
}

/// The ```toml blocks of a Markdown text, or of `//!` doc comments.
fn docs_toml_blocks(text: &str) -> Vec<String> {
    let mut blocks = Vec::new();
    let mut current: Option<String> = None;
    for line in text.lines() {
        let line = line
            .strip_prefix("//!")
            .map_or(line, |l| l.strip_prefix(' ').unwrap_or(l));
        if current.is_none() && line.trim_start().starts_with("```toml") {
            current = Some(String::new());
        } else if current.is_some() && line.trim_start().starts_with("```") {
            blocks.push(current.take().expect("inside a block"));
        } else if let Some(block) = current.as_mut() {
            block.push_str(line);
            block.push('\n');
        }
    }
    blocks
}

#[test]
fn every_documented_config_key_parses_and_every_config_key_is_documented() {
    let doc_file = "docs/config.md";
    let keys = docs_config_keys(&docs_read(doc_file));
    assert!(
        keys.len() >= 10,
        "{doc_file}: only {} keys found: the page's table format no longer matches this test",
        keys.len()
    );
    let path = Path::new(doc_file);
    let mut problems = Vec::new();

    // Documented → accepted by the parser. A table whose keys are all required
    // (`[calibration]`) is retried with every documented key of that table.
    for key in &keys {
        let alone = docs_toml(&[key]);
        let parsed = match ExperimentConfig::parse(&alone, path) {
            Err(e) if e.to_string().contains("missing field") => {
                let siblings: Vec<&DocKey> = keys.iter().filter(|k| k.table == key.table).collect();
                ExperimentConfig::parse(&docs_toml(&siblings), path)
            }
            other => other,
        };
        if let Err(e) = parsed {
            problems.push(format!(
                "{doc_file}: key `{}` with its example `{}` is rejected by the config parser: {e}",
                key.dotted(),
                key.example
            ));
        }
    }

    // The parser's check is meaningful only if it rejects keys it does not know.
    for made_up in [
        "fsp = 480\n",
        "[fit]\nwindows_s = 0.5\n",
        "[disk]\nradius = 0.04\n",
    ] {
        assert!(
            ExperimentConfig::parse(made_up, path).is_err(),
            "the config parser accepted the made-up key in {made_up:?}: unknown keys are no \
             longer rejected, so {doc_file}'s rows are not checked against the code"
        );
    }

    // Code → documented: every field of a fully populated config. The struct
    // literals name every field (no `..Default::default()`), so a new field fails to
    // compile here until it is added, and then fails below until it is documented.
    let full = ExperimentConfig {
        fps: Some(480.0),
        plate: Some(Plate::Dark),
        two_view: Some(false),
        material: Some("stainless steel".into()),
        disk_name: Some("euler".into()),
        orientation: Some("flipped".into()),
        disk: Some(DiskConfig {
            preset: Some(Preset::EulerDisk),
            mass_kg: Some(0.443),
            radius_m: Some(0.0381),
            half_thickness_m: Some(0.00635),
            inertia_a_kg_m2: Some(1.62e-4),
            inertia_c_kg_m2: Some(3.22e-4),
        }),
        camera_distance_m: Some(0.35),
        vision: Some(VisionConfig {
            gamma: Some(0.35),
            band_half_width_px: Some(3),
            split_row: Some(640),
            roi: Some([0, 0, 720, 1280]),
        }),
        calibration: Some(CalibrationConfig {
            x_l: 112.0,
            x_r: 608.0,
            z_t: 700.0,
            z_base: 742.0,
        }),
        fit: Some(FitConfig {
            window_s: Some(0.5),
            halt: Some(HaltChoice::Combined),
            rim_zero: Some(RimZeroChoice::Motion),
            rim_zero_uncertainty_px: Some(0.08),
        }),
    };
    let documented: BTreeSet<String> = keys.iter().map(DocKey::dotted).collect();
    let mut in_code = BTreeSet::new();
    match toml::Value::try_from(&full).expect("the config serialises") {
        toml::Value::Table(t) => docs_toml_paths(&t, "", &mut in_code),
        other => panic!("the config serialised to {other:?}, not a table"),
    }
    for key in in_code.difference(&documented) {
        problems.push(format!(
            "{doc_file}: config key `{key}` (a field of ExperimentConfig in src/config.rs) is not documented"
        ));
    }

    // The examples users copy: every key they set is documented, and they parse.
    for source in ["README.md", "docs/config.md", "src/config.rs"] {
        for block in docs_toml_blocks(&docs_read(source)) {
            let Ok(table) = block.parse::<toml::Table>() else {
                problems.push(format!(
                    "{source}: a ```toml example is not valid TOML:\n{block}"
                ));
                continue;
            };
            if let Err(e) = ExperimentConfig::parse(&block, Path::new(source)) {
                problems.push(format!(
                    "{source}: a ```toml example is rejected by the config parser: {e}"
                ));
            }
            let mut paths = BTreeSet::new();
            docs_toml_paths(&table, "", &mut paths);
            for key in paths.difference(&documented) {
                problems.push(format!(
                    "{source}: its ```toml example sets `{key}`, which {doc_file} does not document"
                ));
            }
        }
    }
    assert!(problems.is_empty(), "{}", problems.join("\n"));
}
