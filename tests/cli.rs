//! The `eulerdisk` binary end to end, each test in a fresh temporary folder.

use crate::util::eulerdisk;

/// `simulate` with the thesis's contour-friction run writes the CSV, the JSON summary
/// and the plot panel, and the summary carries the physics: the end on θ̇ = 0 with
/// φ ≈ 3.1e-5 (§4.7; ±5 % for the two printed figures).
#[test]
fn simulate_contour_writes_outputs_with_thesis_end_state() {
    let dir = tempfile::tempdir().unwrap();
    let out = eulerdisk(
        dir.path(),
        &[
            "simulate", "--model", "contour", "--eta", "2.43e-4", "-o", "run",
        ],
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    for file in ["trajectory.csv", "summary.json", "panel.svg", "panel.png"] {
        assert!(
            dir.path().join("run").join(file).is_file(),
            "{file} missing"
        );
    }
    let summary: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.path().join("run/summary.json")).unwrap())
            .unwrap();
    assert_eq!(summary["end_reason"], "discontinuity-set");
    let phi = summary["end_phi"].as_f64().unwrap();
    assert!((phi / 3.1e-5 - 1.0).abs() < 0.05, "φ_end = {phi}");
    assert!(
        summary["slip_phase_count"].as_u64().unwrap() > 1,
        "fig. 4.13 shows many slip phases"
    );
    // The CSV has one row per 0.1 ms sample plus events, with the energy column.
    let csv = std::fs::read_to_string(dir.path().join("run/trajectory.csv")).unwrap();
    assert!(csv.lines().next().unwrap().contains("energy"));
    assert!(csv.lines().count() > 4700, "≈ 0.47 s at 0.1 ms");
}

/// A model without η or --stop-at is refused with a message that says what to give.
#[test]
fn simulate_without_eta_is_a_clear_error() {
    let dir = tempfile::tempdir().unwrap();
    let out = eulerdisk(dir.path(), &["simulate", "--model", "contour"]);
    assert!(!out.status.success());
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        stderr.contains("--eta") && stderr.contains("--stop-at"),
        "{stderr}"
    );
}

/// Impossible initial conditions name the quantity.
#[test]
fn simulate_rejects_bad_initial_angle() {
    let dir = tempfile::tempdir().unwrap();
    let out = eulerdisk(dir.path(), &["simulate", "--model", "none", "--phi", "2.0"]);
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("initial φ"));
}

/// `info` on a missing clip fails and names the file.
#[test]
fn info_missing_clip_names_the_file() {
    let dir = tempfile::tempdir().unwrap();
    let out = eulerdisk(dir.path(), &["info", "no-such-clip.mp4"]);
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("no-such-clip.mp4"));
}

/// An error that quotes its I/O cause names it once (issue 13.6: "os error"
/// printed twice): an output folder under a path that cannot hold one.
#[test]
fn an_io_error_is_named_once() {
    let dir = tempfile::tempdir().unwrap();
    let fixture = crate::util::fixture("side-dark-n050.mp4");
    let out = eulerdisk(
        dir.path(),
        &[
            "analyse",
            fixture.to_str().unwrap(),
            "-o",
            "/proc/eulerdisk-cannot-write-here",
        ],
    );
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("/proc/"), "{err}");
    assert_eq!(err.matches("os error").count(), 1, "{err}");
}

/// `reproduce --skip-table-4-1` writes the table, and its Painlevé row is eq. 4.48 at
/// λ = 4.08 (1.105; the thesis prints 1.11).
#[test]
fn reproduce_writes_table() {
    let dir = tempfile::tempdir().unwrap();
    let out = eulerdisk(dir.path(), &["reproduce", "--skip-table-4-1", "-o", "rep"]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let json: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.path().join("rep/reproduce.json")).unwrap())
            .unwrap();
    let rows = json["rows"].as_array().unwrap();
    let painleve = rows
        .iter()
        .find(|r| r["quantity"].as_str().unwrap().contains("μ_p"))
        .unwrap();
    assert!((painleve["ours"].as_f64().unwrap() - 1.105).abs() < 1e-3);
    assert!(dir.path().join("rep/reproduce.md").is_file());
}

fn stderr(out: &std::process::Output) -> String {
    String::from_utf8_lossy(&out.stderr).into_owned()
}

/// Issue 13.1, 13.5, 13.6, 13.7 on one analysed fixture: `analyse a/run1.mp4;
/// analyse b/run1.mp4` silently replaced the first result (now refused, naming
/// both clips); `-c` naming a folder said "no such file"; an output path that is a
/// file said "File exists (os error 17)"; `compare` accepted `--contact-gap=-1`
/// (a post-flat time of −2.48e9 s), φ = 3 rad and a peak after the halt; and the
/// JSON outputs were 0600 whatever the umask.
#[test]
fn analyse_and_compare_refuse_what_would_mix_or_mislead() {
    let dir = tempfile::tempdir().unwrap();
    let fixtures = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures");
    for (clip, fixture) in [
        ("a/run1.mp4", "side-dark-n050.mp4"),
        ("b/run1.mp4", "two-view-n045.mp4"),
        ("c/run1.mp4", "side-dark-n050.mp4"),
    ] {
        let path = dir.path().join(clip);
        std::fs::create_dir_all(path.parent().unwrap()).unwrap();
        std::fs::copy(fixtures.join(fixture), &path).unwrap();
    }
    std::fs::write(dir.path().join("plain"), b"x").unwrap();
    std::fs::create_dir(dir.path().join("configs")).unwrap();

    let out = eulerdisk(dir.path(), &["analyse", "a/run1.mp4", "-c", "configs"]);
    assert!(
        stderr(&out).contains("a folder, not a config file"),
        "{}",
        stderr(&out)
    );
    let out = eulerdisk(dir.path(), &["analyse", "a/run1.mp4", "-o", "plain/x"]);
    let err = stderr(&out);
    assert!(
        err.contains("plain") && err.contains("is a file") && !err.contains("os error"),
        "{err}"
    );

    let out = eulerdisk(dir.path(), &["analyse", "a/run1.mp4"]);
    assert!(out.status.success(), "{}", stderr(&out));
    let experiment = dir.path().join("out/run1.mp4");
    let result = experiment.join("result.json");
    use std::os::unix::fs::PermissionsExt;
    let mode = |p: &std::path::Path| p.metadata().unwrap().permissions().mode() & 0o777;
    assert_eq!(
        mode(&result),
        mode(&dir.path().join("plain")),
        "the umask's permissions"
    );

    let out = eulerdisk(dir.path(), &["analyse", "b/run1.mp4"]);
    assert_eq!(out.status.code(), Some(1));
    let err = stderr(&out);
    assert!(
        err.contains("a/run1.mp4") && err.contains("b/run1.mp4"),
        "{err}"
    );
    // An identical copy is the same clip: no refusal.
    let out = eulerdisk(dir.path(), &["analyse", "c/run1.mp4"]);
    assert!(out.status.success(), "{}", stderr(&out));

    let out = eulerdisk(
        dir.path(),
        &[
            "compare",
            "out/run1.mp4",
            "--model",
            "contour",
            "--contact-gap=-1",
        ],
    );
    assert!(stderr(&out).contains("--contact-gap"), "{}", stderr(&out));

    let original: serde_json::Value =
        serde_json::from_slice(&std::fs::read(&result).unwrap()).unwrap();
    for (field, value, words) in [
        ("phi", 3.0, "outside [0, π/2)"),
        ("t", 0.5, "after the halt"),
    ] {
        let mut edited = original.clone();
        edited["series"]["peaks"]["peaks"][0][field] = value.into();
        std::fs::write(&result, serde_json::to_vec(&edited).unwrap()).unwrap();
        let out = eulerdisk(
            dir.path(),
            &["compare", "out/run1.mp4", "--model", "contour"],
        );
        assert!(!out.status.success());
        assert!(stderr(&out).contains(words), "{field}: {}", stderr(&out));
    }
}

/// Issue 13.7: a folder the user cannot write is an error naming it, not a panic.
/// Root writes anywhere (CAP_DAC_OVERRIDE), so a privileged test runs a copy of the
/// binary (the build's folders may be closed to others) as `nobody` (uid and gid
/// 65534, the permissions a lab user has): the folder is then as read-only to it as
/// to any user. Where root cannot start a process as `nobody`, the test fails and
/// says so.
#[test]
fn a_read_only_output_folder_is_an_error_naming_it() {
    use std::os::unix::fs::PermissionsExt;
    use std::os::unix::process::CommandExt;
    let dir = tempfile::tempdir().unwrap();
    let locked = dir.path().join("locked");
    std::fs::create_dir(&locked).unwrap();
    std::fs::set_permissions(&locked, std::fs::Permissions::from_mode(0o555)).unwrap();
    let privileged = std::fs::write(locked.join("probe"), b"x").is_ok();
    let mut program = std::path::PathBuf::from(env!("CARGO_BIN_EXE_eulerdisk"));
    if privileged {
        std::fs::remove_file(locked.join("probe")).unwrap();
        // `nobody` must reach the working folder (a temporary folder is 0700) and
        // the binary.
        std::fs::set_permissions(dir.path(), std::fs::Permissions::from_mode(0o755)).unwrap();
        let copy = dir.path().join("eulerdisk");
        std::fs::copy(&program, &copy).unwrap();
        program = copy;
    }
    let mut command = std::process::Command::new(&program);
    command.args([
        "simulate",
        "--model",
        "none",
        "--t-end",
        "0.01",
        "-o",
        "locked/run",
    ]);
    command.current_dir(dir.path());
    if privileged {
        command.uid(65534).gid(65534);
    }
    let out = command.output().unwrap_or_else(|e| {
        if privileged {
            panic!(
                "running as root, which writes into any folder, and cannot run the binary \
                 as nobody (uid 65534) to see a read-only folder as a user does: {e}; \
                 run the tests as an ordinary user"
            )
        }
        panic!("run eulerdisk: {e}")
    });
    assert_eq!(out.status.code(), Some(1), "{}", stderr(&out));
    let err = stderr(&out);
    assert!(
        err.contains("locked") && err.contains("ermission denied"),
        "{err}"
    );
    // Nothing was written into the folder.
    assert_eq!(std::fs::read_dir(&locked).unwrap().count(), 0);
}

/// Issue 13.4: `simulate --model none --t-end 1e9` grew without limit (481 MB after
/// 36 s), `--psi-dot 1e9` and `--stop-at 1e9` ran past 120 s, and `render --size
/// 100000x100000` aborted with an allocation failure. Each now stops with an error
/// that names the bound: the first after MAX_SAMPLES output samples (100 s of motion
/// at the default 0.1 ms, streamed to the CSV in constant memory:
/// tests/simulate_stream.rs); with coarse samples, after MAX_STEPS integrator steps
/// (about 5 000 s of Coulomb-only motion); the others before any work.
#[test]
fn simulate_and_render_bound_their_work() {
    let dir = tempfile::tempdir().unwrap();
    let runs = [
        (
            &["simulate", "--model", "none", "--t-end", "1e9"][..],
            "1000000 output samples reached",
        ),
        (
            &[
                "simulate", "--model", "none", "--t-end", "1e9", "--dt", "1000",
            ][..],
            "no progress: 5000000 integrator steps",
        ),
        (
            &["simulate", "--model", "none", "--psi-dot", "1e9"][..],
            "speed of sound",
        ),
        (
            &["simulate", "--model", "contour", "--stop-at", "1e9"][..],
            "between 0 and 50 s",
        ),
        (
            &["render", "--size", "100000x100000", "-o", "big.mp4"][..],
            "exceed the limit",
        ),
        (
            &["render", "--halt", "1e9", "-o", "long.mp4"][..],
            "at most 100000 frames",
        ),
    ]
    .map(|(args, words)| {
        // All at once: the step-bound run takes some seconds.
        let child = std::process::Command::new(env!("CARGO_BIN_EXE_eulerdisk"))
            .args(args)
            .current_dir(dir.path())
            .stdout(std::process::Stdio::piped())
            .stderr(std::process::Stdio::piped())
            .spawn()
            .expect("run eulerdisk");
        (args, words, child)
    });
    for (args, words, child) in runs {
        let out = child.wait_with_output().unwrap();
        assert_eq!(out.status.code(), Some(1), "{args:?}");
        let err = stderr(&out);
        assert!(
            err.contains(words) && !err.contains("panicked"),
            "{args:?}: {err}"
        );
    }
}
