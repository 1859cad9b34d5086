//! The peak resident size of a stage, alone in its process: this file holds one test, so no
//! other test thread allocates or frees memory while it reads `VmRSS`/`VmHWM`. (In the
//! library's unit tests it shared the process with other tests' threads: a neighbour freeing
//! memory between the reading before the stage and the stage made it fail.)
#![cfg(target_os = "linux")]

use demcon_core::{Stages, available_memory, resident_bytes};

/// The peak of a stage that allocates 64 MiB (touched) is at least 60 MiB above the resident
/// size before it; and, where the kernel lets the peak be reset, the next stage, which
/// allocates nothing, no longer sees those 64 MiB (its peak is its own).
#[test]
fn the_peak_of_a_stage_sees_what_it_allocated() {
    let before = resident_bytes().0.unwrap();
    let mut s = Stages::new(None);
    s.time("alloc", || {
        let v = vec![1u8; 64 << 20];
        std::hint::black_box(&v);
    });
    s.time("idle", || ());
    let (alloc, idle) = (&s.records()[0], &s.records()[1]);
    assert!(
        alloc.peak_rss_bytes.unwrap() >= before + (60 << 20),
        "{alloc:?}, before {before}"
    );
    if idle.peak_is_stage {
        assert!(
            idle.peak_rss_bytes.unwrap() < before + (32 << 20),
            "{idle:?}, before {before}"
        );
    }
    assert!(available_memory().unwrap() > 0);
}
