//! The `eulerdisk` binary end to end, each test in a fresh temporary folder.

mod util;
use util::eulerdisk;

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
