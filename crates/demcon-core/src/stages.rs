//! The stages of a run: wall time and resident memory of each, and an observer that shows
//! them as they happen (a progress display).
//!
//! Memory is read from `/proc/self/status` (Linux): the resident set after the stage
//! (`VmRSS`) and its peak during the stage (`VmHWM`, reset at the start of each stage by
//! writing `5` to `/proc/self/clear_refs`). Elsewhere, or when the kernel refuses the reset,
//! the values are `None` or the peak since the process started, and say so
//! ([`StageRecord::peak_is_stage`]).

use std::sync::Arc;
use std::time::Instant;

/// Wall time and memory of one stage.
#[derive(Debug, Clone, PartialEq)]
pub struct StageRecord {
    /// The stage (`packing`, `tessellation`, `solve`, …).
    pub stage: &'static str,
    /// Wall time (s).
    pub wall_s: f64,
    /// Resident set size after the stage (bytes), when the system tells.
    pub rss_bytes: Option<u64>,
    /// Peak resident set size (bytes), when the system tells: during the stage if
    /// [`peak_is_stage`](Self::peak_is_stage), else since the process started.
    pub peak_rss_bytes: Option<u64>,
    /// Whether `peak_rss_bytes` is the peak of this stage alone (the reset worked).
    pub peak_is_stage: bool,
}

/// Watches the stages of a run as they start and end (e.g. a progress display).
pub trait StageObserver: Send + Sync {
    /// Stage `stage` begins.
    fn started(&self, stage: &'static str);
    /// A stage ended, with its record.
    fn finished(&self, record: &StageRecord);
}

/// The stages of a run, in order, with an optional observer.
#[derive(Clone, Default)]
pub struct Stages {
    records: Vec<StageRecord>,
    observer: Option<Arc<dyn StageObserver>>,
}

impl std::fmt::Debug for Stages {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Stages")
            .field("records", &self.records)
            .field("observer", &self.observer.is_some())
            .finish()
    }
}

impl Stages {
    /// No stages yet; `observer` (if any) sees each one start and end.
    pub fn new(observer: Option<Arc<dyn StageObserver>>) -> Self {
        Self {
            records: Vec::new(),
            observer,
        }
    }

    /// Runs `f` as stage `stage`, recording its wall time and memory.
    pub fn time<T>(&mut self, stage: &'static str, f: impl FnOnce() -> T) -> T {
        if let Some(o) = &self.observer {
            o.started(stage);
        }
        let peak_is_stage = reset_peak_resident();
        let t0 = Instant::now();
        let out = f();
        release_free_memory();
        let wall_s = t0.elapsed().as_secs_f64();
        let (rss_bytes, peak_rss_bytes) = resident_bytes();
        self.push(StageRecord {
            stage,
            wall_s,
            rss_bytes,
            peak_rss_bytes,
            peak_is_stage,
        });
        out
    }

    /// Adds a stage timed elsewhere.
    pub fn push(&mut self, record: StageRecord) {
        if let Some(o) = &self.observer {
            o.finished(&record);
        }
        self.records.push(record);
    }

    /// The stages so far, in order.
    pub fn records(&self) -> &[StageRecord] {
        &self.records
    }

    /// The wall time of `stage` (s), summed over its runs; 0 if it did not run.
    pub fn wall_s(&self, stage: &str) -> f64 {
        self.records
            .iter()
            .filter(|s| s.stage == stage)
            .map(|s| s.wall_s)
            .sum()
    }

    /// The largest peak resident size of any stage (bytes), when the system tells.
    pub fn peak_rss_bytes(&self) -> Option<u64> {
        self.records.iter().filter_map(|r| r.peak_rss_bytes).max()
    }
}

/// Resident set size now and its peak (bytes): `VmRSS` and `VmHWM` of `/proc/self/status`;
/// `None` where that file does not exist.
pub fn resident_bytes() -> (Option<u64>, Option<u64>) {
    let Ok(text) = std::fs::read_to_string("/proc/self/status") else {
        return (None, None);
    };
    let field = |name: &str| {
        text.lines()
            .find_map(|l| l.strip_prefix(name))
            .and_then(|v| v.trim().trim_end_matches("kB").trim().parse::<u64>().ok())
            .map(|kb| kb.saturating_mul(1024))
    };
    (field("VmRSS:"), field("VmHWM:"))
}

/// Hands the allocator's free memory back to the system (glibc's `malloc_trim`), so that
/// what a stage allocated and freed (e.g. the tessellation's per-cell lists) does not stay
/// resident for the rest of the run: the freed small blocks are scattered through the heap,
/// which glibc otherwise keeps. A no-op elsewhere.
pub fn release_free_memory() {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    #[allow(unsafe_code)]
    // SAFETY: `malloc_trim` takes no pointer and only walks the allocator's own free lists,
    // locking each arena; it is safe to call from any thread at any time.
    unsafe {
        libc::malloc_trim(0);
    }
}

/// Resets the peak resident size (`VmHWM`) to the current one; false where the system does
/// not allow it.
pub fn reset_peak_resident() -> bool {
    std::fs::write("/proc/self/clear_refs", "5").is_ok()
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::Mutex;

    #[derive(Default)]
    struct Log(Mutex<Vec<String>>);

    impl StageObserver for Log {
        fn started(&self, stage: &'static str) {
            self.0.lock().unwrap().push(format!("start {stage}"));
        }
        fn finished(&self, r: &StageRecord) {
            self.0.lock().unwrap().push(format!("end {}", r.stage));
        }
    }

    #[test]
    fn records_stages_in_order_and_tells_the_observer() {
        let log = Arc::new(Log::default());
        let mut s = Stages::new(Some(log.clone()));
        let v = s.time("a", || 2 + 2);
        s.time("b", || ());
        s.time("a", || ());
        assert_eq!(v, 4);
        assert_eq!(
            s.records().iter().map(|r| r.stage).collect::<Vec<_>>(),
            ["a", "b", "a"]
        );
        assert_eq!(
            *log.0.lock().unwrap(),
            ["start a", "end a", "start b", "end b", "start a", "end a"]
        );
        assert!(s.wall_s("a") >= 0.0 && s.wall_s("c") == 0.0);
    }

    // The peak of a stage is checked in `tests/stage_peak.rs`, a process of its own: other
    // test threads would share the resident size it reads.
}
