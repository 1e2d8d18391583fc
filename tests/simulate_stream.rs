//! Issue 13.4: `simulate` streams its trajectory. `simulate --model none --t-end
//! 1e9` grew without limit (481 MB after 36 s): the samples were kept in memory
//! until the run ended. Now each goes to the CSV as it is produced, and the plot
//! keeps a bounded envelope. The test counts every heap allocation of its process (a
//! counting global allocator, read only in a process running this test alone: the
//! test runs itself again as a child, so no other test's allocations are counted)
//! and checks that a run 10× longer takes no more heap at its peak, while its CSV
//! holds every sample and the physics of the long run holds: energy conserved while
//! rolling without dissipation, lost only while slipping.

use std::alloc::{GlobalAlloc, Layout, System};
use std::io::BufRead;
use std::sync::atomic::{AtomicUsize, Ordering};

use eulerdisk::model::dissipation::{Dissipation, ModelKind};
use eulerdisk::model::dynamics::Mode;
use eulerdisk::model::params::Preset;
use eulerdisk::model::simulate::{EndReason, SimulationSpec, simulate_streaming};
use eulerdisk::report::simulation::TrajectoryWriter;

/// The system allocator, counting the bytes live and their peak.
struct Counting;

static LIVE: AtomicUsize = AtomicUsize::new(0);
static PEAK: AtomicUsize = AtomicUsize::new(0);

fn grew(size: usize) {
    let now = LIVE.fetch_add(size, Ordering::Relaxed) + size;
    PEAK.fetch_max(now, Ordering::Relaxed);
}

// SAFETY: every call is passed on to `System` unchanged; only counters are added.
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        // SAFETY: the caller's contract for `alloc` holds for `System.alloc`.
        let p = unsafe { System.alloc(layout) };
        if !p.is_null() {
            grew(layout.size());
        }
        p
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: `ptr` was allocated by `System` with `layout`.
        unsafe { System.dealloc(ptr, layout) };
        LIVE.fetch_sub(layout.size(), Ordering::Relaxed);
    }

    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        // SAFETY: the caller's contract for `realloc` holds for `System.realloc`.
        let p = unsafe { System.realloc(ptr, layout, new_size) };
        if !p.is_null() {
            LIVE.fetch_sub(layout.size(), Ordering::Relaxed);
            grew(new_size);
        }
        p
    }
}

#[global_allocator]
static ALLOCATOR: Counting = Counting;

/// What one streamed run to `t_end` left: samples, CSV rows, switches, the peak heap
/// above the start [bytes].
struct Run {
    samples: usize,
    rows: usize,
    switches: usize,
    end_t: f64,
    end_reason: EndReason,
    peak_heap: usize,
}

/// `simulate --model none --t-end T -o DIR` as `main` runs it, in process. While
/// rolling, every sample's energy must equal the first rolling sample's within
/// 1e-9 relative (no dissipation, no slip: eq. 4.94 is conserved; DOP853 at 1e-12
/// keeps 3e-11 over 50 s); while slipping, energy must not rise (Coulomb friction
/// only takes it).
fn run(t_end: f64) -> Run {
    let dir = tempfile::tempdir().unwrap();
    let mut spec = SimulationSpec::thesis_default(
        Preset::EulerDisk.params(),
        Dissipation::new(ModelKind::None),
        0.0,
    );
    spec.t_end = t_end;
    spec.output_interval = 1e-4;

    let start = LIVE.load(Ordering::Relaxed);
    PEAK.store(start, Ordering::Relaxed);
    let mut writer = TrajectoryWriter::create(dir.path()).unwrap();
    let mut rolling_energy: Option<f64> = None;
    let mut last_slip_energy = f64::INFINITY;
    let mut samples = 0usize;
    let run = simulate_streaming(&spec, &mut |s| {
        samples += 1;
        match s.mode {
            Mode::Rolling => {
                let e0 = *rolling_energy.get_or_insert(s.energy);
                if ((s.energy - e0) / e0).abs() > 1e-9 {
                    return Err(format!(
                        "rolling energy {} at t = {} (first {e0})",
                        s.energy, s.t
                    ));
                }
            }
            Mode::Slipping => {
                if s.energy > last_slip_energy * (1.0 + 1e-12) {
                    return Err(format!(
                        "slipping energy rose to {} at t = {}",
                        s.energy, s.t
                    ));
                }
                last_slip_energy = s.energy;
            }
        }
        writer.push(s).map_err(|e| e.to_string())
    })
    .unwrap();
    writer.finish("stream test", &spec, &run).unwrap();
    let peak_heap = PEAK.load(Ordering::Relaxed) - start;

    assert!(rolling_energy.is_some(), "the run never rolled");
    let csv = std::fs::File::open(dir.path().join("trajectory.csv")).unwrap();
    let rows = std::io::BufReader::new(csv).lines().count() - 1;
    Run {
        samples,
        rows,
        switches: run.phases.len() - 1,
        end_t: run.end.t,
        end_reason: run.end_reason,
        peak_heap,
    }
}

/// Set in the child process that runs the test alone.
const ALONE: &str = "EULERDISK_TEST_ALLOCATIONS_ALONE";

#[test]
fn a_ten_times_longer_run_streams_in_the_same_memory() {
    if std::env::var_os(ALONE).is_none() {
        // Other tests allocate beside this one in this process: run the binary
        // again with this test alone, whose allocations are then all counted.
        let name = "simulate_stream::a_ten_times_longer_run_streams_in_the_same_memory";
        let out = std::process::Command::new(std::env::current_exe().unwrap())
            .args([name, "--exact", "--test-threads=1", "--nocapture"])
            .env(ALONE, "1")
            .output()
            .expect("run the test binary again");
        let stdout = String::from_utf8_lossy(&out.stdout);
        assert!(
            out.status.success() && stdout.contains("1 passed"),
            "the test alone in a child process:\n{stdout}\n{}",
            String::from_utf8_lossy(&out.stderr)
        );
        return;
    }
    let short = run(5.0);
    let long = run(50.0);
    for (t_end, r) in [(5.0, &short), (50.0, &long)] {
        assert_eq!(r.end_reason, EndReason::TimeLimit);
        assert_eq!(r.end_t, t_end);
        // Every sample is a CSV row.
        assert_eq!(r.rows, r.samples);
        // Uniform samples at 0, 0.1 ms, … to t_end, one at each switch of mode,
        // the final state. The output times are summed step by step, so the one at
        // t_end may fall just past it, where the final sample stands: one fewer.
        let most = (t_end / 1e-4).round() as usize + 1 + r.switches + 1;
        assert!(
            r.rows == most || r.rows + 1 == most,
            "{} rows, {most} at most",
            r.rows
        );
    }
    // The long run holds no more at its peak than the short one: nothing kept per
    // sample (before streaming: 100 MB more for the 450 000 more samples).
    // 256 KiB: allocator and buffer noise.
    assert!(
        long.peak_heap <= short.peak_heap + 256 * 1024,
        "peak heap {} B for 50 s, {} B for 5 s",
        long.peak_heap,
        short.peak_heap
    );
    // And it is small: the envelope of 4096 buckets, the CSV's buffers, the panel.
    assert!(long.peak_heap < 32 << 20, "peak heap {} B", long.peak_heap);
}
