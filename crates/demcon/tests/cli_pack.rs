//! End-to-end robustness tests of `demcon pack`, `tile`, `info` and `calibrate` (fuzz findings):
//! bad input is refused up front with the flag, the value and what is allowed; budget stops
//! exit with status 3; outputs are checked before packing and written all or none.

mod common;

use std::process::Output;

use common::{demcon, text};

/// `pack` into `out` with a small valid setup, `extra` flags replacing or adding to it.
fn pack(out: &str, extra: &[&str]) -> Output {
    let base = [
        ("--container", "box"),
        ("--size", "0.01,0.01,0.01"),
        ("--count", "300"),
        ("--phi", "0.55"),
        ("--out", out),
    ];
    let mut args = vec!["pack", "--quiet"];
    for (flag, value) in base {
        if !extra.contains(&flag) {
            args.extend([flag, value]);
        }
    }
    args.extend_from_slice(extra);
    demcon(&args)
}

#[test]
fn pack_refuses_underflowing_sizes() {
    let d = common::scratch("clipack", "underflow");
    let out = d.join("p.xyzr");
    let o_s = out.to_str().unwrap();
    for (flags, want) in [
        (
            vec!["--size", "1e-300,1e-300,1e-300"],
            "container.size.x = 1e-300 m",
        ),
        (vec!["--phi", "4.9e-324"], "phi = 5e-324"),
    ] {
        let o = pack(o_s, &flags);
        assert_eq!(o.status.code(), Some(1), "{}", text(&o));
        assert!(text(&o).contains(want), "{}", text(&o));
        assert!(text(&o).len() < 600, "{}", text(&o));
        assert!(!out.exists());
    }
    std::fs::remove_dir_all(&d).unwrap();
}

#[test]
fn pack_refuses_growth_rates_and_skins_that_never_finish() {
    let d = common::scratch("clipack", "growth");
    let out = d.join("p.xyzr");
    let o_s = out.to_str().unwrap();
    for (flags, want) in [
        (["--growth-rate", "1e308"], "growth-rate = 1e308"),
        (["--growth-rate", "1e-308"], "growth-rate = 1e-308"),
        (["--neighbour-skin", "1e-308"], "neighbour-skin = 1e-308"),
    ] {
        let o = pack(o_s, &flags);
        assert_eq!(o.status.code(), Some(1), "{}", text(&o));
        assert!(
            text(&o).contains(want) && text(&o).contains("must be in ["),
            "{}",
            text(&o)
        );
    }
    std::fs::remove_dir_all(&d).unwrap();
}

#[test]
fn threads_and_count_are_bounded() {
    let d = common::scratch("clipack", "bounds");
    let out = d.join("p.xyzr");
    let o = pack(out.to_str().unwrap(), &["--count", "4000000000"]);
    assert_eq!(o.status.code(), Some(1), "{}", text(&o));
    assert!(text(&o).contains("bytes per particle"), "{}", text(&o));
    let o = demcon(&["calibrate", "--packing", "x.xyzr", "--threads", "10000"]);
    assert_eq!(o.status.code(), Some(1), "{}", text(&o));
    assert!(
        text(&o).contains("--threads 10000: must be between 1 and"),
        "{}",
        text(&o)
    );
    std::fs::remove_dir_all(&d).unwrap();
}

#[test]
fn budget_stops_exit_3_and_say_which_budget() {
    let d = common::scratch("clipack", "budget");
    let out = d.join("p.xyzr");
    let o_s = out.to_str().unwrap();
    // Above the floor (at least the events 300 particles need to reach 0.6, halved), still
    // short of what they take: the run stops on its budget.
    let floor = demcon_packing::min_events(300, 0.6);
    let budget = (floor + 1).to_string();
    let o = pack(o_s, &["--phi", "0.6", "--max-events", &budget]);
    assert_eq!(o.status.code(), Some(3), "{}", text(&o));
    assert!(text(&o).contains("event budget"), "{}", text(&o));
    assert!(!text(&o).contains("overlap by"), "{}", text(&o));
    for g in ["0.5", "1"] {
        let o = pack(o_s, &["--growth-rate", g, "--allow-short"]);
        assert!(o.status.success(), "{}", text(&o));
    }
    std::fs::remove_dir_all(&d).unwrap();
}

#[test]
fn budgets_that_cannot_reach_the_target_are_refused_before_packing() {
    let d = common::scratch("clipack", "budget-floor");
    let out = d.join("p.xyzr");
    let o_s = out.to_str().unwrap();
    for (flags, want) in [
        (["--max-events", "100"], "invalid max-events = 100"),
        (["--max-time", "1e-9"], "invalid max-time = 0.000000001 s"),
    ] {
        let o = pack(o_s, &flags);
        assert_eq!(o.status.code(), Some(1), "{}", text(&o));
        let msg = text(&o);
        assert!(
            msg.contains(want) && msg.contains("--phi") && msg.contains("Budgets"),
            "{msg}"
        );
        assert!(!out.exists(), "nothing packed or written");
    }
    std::fs::remove_dir_all(&d).unwrap();
}

#[test]
fn output_paths_are_checked_before_packing() {
    let d = common::scratch("clipack", "outputs");
    let out = d.join("p.xyzr");
    let o = pack("/nonexistent/x", &[]);
    assert_eq!(o.status.code(), Some(1), "{}", text(&o));
    assert!(
        text(&o).contains("--out") && text(&o).contains("does not exist"),
        "{}",
        text(&o)
    );
    assert!(
        !text(&o).contains("phi (overall)"),
        "packed before failing: {}",
        text(&o)
    );
    let o = pack(out.to_str().unwrap(), &["--report-json", "/nonexistent/r.json"]);
    assert_eq!(o.status.code(), Some(1), "{}", text(&o));
    assert!(text(&o).contains("--report-json"), "{}", text(&o));
    assert!(!out.exists(), "a partial set of outputs was left");
    let report = d.join("r.json");
    let o = pack(
        out.to_str().unwrap(),
        &["--report-json", report.to_str().unwrap()],
    );
    assert!(o.status.success(), "{}", text(&o));
    assert!(out.exists() && report.exists());
    let names: Vec<_> = std::fs::read_dir(&d)
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    assert_eq!(names.len(), 2, "temporaries left: {names:?}");
    std::fs::remove_dir_all(&d).unwrap();
}

#[test]
fn calibrate_refuses_zero_realisations() {
    let o = demcon(&["calibrate", "--packing", "x.xyzr", "--realisations", "0"]);
    assert_eq!(o.status.code(), Some(1), "{}", text(&o));
    assert!(text(&o).contains("--realisations 0"), "{}", text(&o));
}

#[test]
fn info_refuses_truncated_outside_and_impossible_files() {
    let d = common::scratch("clipack", "info");
    let f = d.join("p.xyzr");
    for (body, want) in [
        (
            "# container box 0.01 0.01 0.01\n# count 3\n0.005 0.005 0.005 0.001\n",
            "`# count 3` but the file has 1 particle lines",
        ),
        (
            "# container box 0.01 0.01 0.01\n1 0.005 0.005 0.001\n",
            "p.xyzr:2: particle 0 (centre (1, 0.005, 0.005) m",
        ),
        (
            "# container periodic 0.001 0.001 0.001\n0.0005 0.0005 0.0005 0.0009\n",
            "volume fraction 3.05",
        ),
    ] {
        std::fs::write(&f, body).unwrap();
        let o = demcon(&["info", f.to_str().unwrap()]);
        assert_eq!(o.status.code(), Some(1), "{}", text(&o));
        assert!(text(&o).contains(want), "{}", text(&o));
    }
    std::fs::remove_dir_all(&d).unwrap();
}

#[test]
fn tile_copies_a_periodic_file_and_refuses_what_it_cannot_tile() {
    let d = common::scratch("clipack", "tile");
    let (p, b, t) = (d.join("p.xyzr"), d.join("b.xyzr"), d.join("t.xyzr"));
    let (p_s, b_s, t_s) = (p.to_str().unwrap(), b.to_str().unwrap(), t.to_str().unwrap());
    let o = pack(p_s, &["--container", "periodic", "--size", "0.001,0.001,0.001"]);
    assert!(o.status.success(), "{}", text(&o));
    let o = demcon(&["tile", p_s, "--repeat", "2,1,3", "--out", t_s]);
    assert!(o.status.success(), "{}", text(&o));
    let tiled = std::fs::read_to_string(&t).unwrap();
    assert!(
        tiled.contains("# container periodic 0.002 0.001 0.003"),
        "{tiled}"
    );
    assert!(tiled.contains("# count 1800"), "{tiled}");
    assert!(text(&o).contains("volume fraction    0.55000"), "{}", text(&o));
    std::fs::remove_file(&t).unwrap();
    let o = pack(b_s, &[]);
    assert!(o.status.success(), "{}", text(&o));
    for (args, want) in [
        (vec!["tile", p_s, "--repeat", "2,0,3"], "repeat[1] = 0"),
        (vec!["tile", p_s, "--repeat", "2,2"], "three counts"),
        (vec!["tile", b_s, "--repeat", "2,2,2"], "only a periodic packing"),
        // 3·10⁹ particles: within the 32-bit ids, beyond any machine's memory.
        (
            vec!["tile", p_s, "--repeat", "1000,1000,10"],
            "tiling needs ~160 bytes per particle of the result",
        ),
    ] {
        let mut args = args;
        args.extend(["--out", t_s]);
        let o = demcon(&args);
        assert_eq!(o.status.code(), Some(1), "{}", text(&o));
        assert!(text(&o).contains(want), "{}", text(&o));
        assert!(!t.exists());
    }
    std::fs::remove_dir_all(&d).unwrap();
}

/// Under `ulimit -v 4000000` (4 GB of address space) `demcon tile --repeat 50,50,50` passed
/// its memory check against MemAvailable (~24 GB) and was then aborted by a failed 3 GB
/// allocation (SIGABRT, exit 134). The check now takes the process's own limit: a refusal,
/// exit 1, naming the limit.
#[test]
fn tile_refuses_what_its_address_space_limit_cannot_hold() {
    let d = common::scratch("clipack", "ulimit");
    let (p, t) = (d.join("p.xyzr"), d.join("t.xyzr"));
    let (p_s, t_s) = (p.to_str().unwrap(), t.to_str().unwrap());
    let o = pack(p_s, &["--container", "periodic", "--size", "0.001,0.001,0.001"]);
    assert!(o.status.success(), "{}", text(&o));
    // 300 × 125 000 = 3.75·10⁷ particles, ~6 GB at 160 bytes each.
    let o = std::process::Command::new("sh")
        .args([
            "-c",
            "ulimit -v 4000000 && exec \"$0\" \"$@\"",
            env!("CARGO_BIN_EXE_demcon"),
            "tile",
            p_s,
            "--repeat",
            "50,50,50",
            "--out",
            t_s,
        ])
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(1), "{}", text(&o));
    let said = text(&o);
    assert!(
        said.contains("tiling needs ~160 bytes per particle")
            && said.contains("RLIMIT_AS")
            && said.contains("ulimit -v")
            && said.contains("at most"),
        "{said}"
    );
    assert!(!t.exists());
    std::fs::remove_dir_all(&d).unwrap();
}
