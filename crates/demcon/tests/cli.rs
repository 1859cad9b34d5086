//! End-to-end tests of the `demcon` binary: `pack` and `info`, determinism of the written
//! file, and bad input (non-zero exit, a clear message, no output file left behind).

mod common;

use common::{demcon, text};

#[test]
fn pack_then_info() {
    let d = common::scratch("cli", "pack");
    let out = d.join("p.xyzr");
    let o = demcon(&[
        "pack",
        "--container",
        "box",
        "--size",
        "1,1,2",
        "--count",
        "300",
        "--phi",
        "0.5",
        "--radius-cov",
        "0.3",
        "--seed",
        "4",
        "--out",
        out.to_str().unwrap(),
        "--quiet",
    ]);
    assert!(o.status.success(), "{}", text(&o));
    let t = text(&o);
    assert!(
        t.contains("target volume fraction reached") && t.contains("events/s"),
        "{t}"
    );
    let first = std::fs::read(&out).unwrap();
    // Same flags, same bytes.
    let o = demcon(&[
        "pack",
        "--container",
        "box",
        "--size",
        "1,1,2",
        "--count",
        "300",
        "--phi",
        "0.5",
        "--radius-cov",
        "0.3",
        "--seed",
        "4",
        "--out",
        out.to_str().unwrap(),
        "--quiet",
    ]);
    assert!(o.status.success());
    assert_eq!(std::fs::read(&out).unwrap(), first);
    let o = demcon(&["info", out.to_str().unwrap()]);
    let t = text(&o);
    assert!(o.status.success(), "{t}");
    assert!(t.contains("particles          300 in a box"), "{t}");
    assert!(t.contains("volume fraction    0.50000"), "{t}");
    assert!(t.contains("seed 4"), "{t}");
    // Other containers through their own flags.
    for flags in [
        vec!["--container", "cylinder", "--radius", "0.5", "--length", "1.5"],
        vec!["--container", "sphere", "--radius", "0.7"],
        vec!["--container", "periodic", "--size", "1,1,1"],
    ] {
        let mut args = vec![
            "pack",
            "--count",
            "200",
            "--phi",
            "0.45",
            "--out",
            out.to_str().unwrap(),
            "--quiet",
        ];
        args.extend(flags);
        let o = demcon(&args);
        assert!(o.status.success(), "{}", text(&o));
    }
    std::fs::remove_dir_all(&d).unwrap();
}

#[test]
fn short_of_target_writes_the_file_and_fails_unless_allowed() {
    let d = common::scratch("cli", "short");
    let out = d.join("p.xyzr");
    let args = [
        "pack",
        "--container",
        "periodic",
        "--size",
        "1,1,1",
        "--count",
        "300",
        "--phi",
        "0.674",
        "--growth-rate",
        "0.1",
        "--out",
        out.to_str().unwrap(),
        "--quiet",
    ];
    let o = demcon(&args);
    assert_eq!(o.status.code(), Some(3), "{}", text(&o));
    assert!(text(&o).contains("NOT reached"), "{}", text(&o));
    assert!(out.exists());
    let mut allowed = args.to_vec();
    allowed.push("--allow-short");
    let o = demcon(&allowed);
    assert!(o.status.success(), "{}", text(&o));
    assert!(text(&o).contains("warning: target φ = 0.674 NOT reached"));
    std::fs::remove_dir_all(&d).unwrap();
}

#[test]
fn bad_input_fails_clearly_and_leaves_no_file() {
    let d = common::scratch("cli", "bad");
    let out = d.join("p.xyzr");
    let o_s = out.to_str().unwrap();
    let base = |extra: &[&'static str]| {
        let mut v: Vec<String> = ["pack", "--out", o_s, "--quiet"]
            .iter()
            .map(|s| s.to_string())
            .collect();
        v.extend(extra.iter().map(|s| s.to_string()));
        v
    };
    let cases: Vec<(Vec<&'static str>, &str)> = vec![
        (
            vec![
                "--container",
                "box",
                "--size",
                "1,1,1",
                "--count",
                "0",
                "--phi",
                "0.5",
            ],
            "count = 0",
        ),
        (
            vec![
                "--container",
                "box",
                "--size",
                "1,1,1",
                "--count",
                "-5",
                "--phi",
                "0.5",
            ],
            "count = -5",
        ),
        (
            vec![
                "--container",
                "box",
                "--size",
                "1,-1,1",
                "--count",
                "10",
                "--phi",
                "0.5",
            ],
            "size.y = -1",
        ),
        (
            vec![
                "--container",
                "box",
                "--size",
                "1,1",
                "--count",
                "10",
                "--phi",
                "0.5",
            ],
            "three lengths",
        ),
        (
            vec!["--container", "box", "--count", "10", "--phi", "0.5"],
            "--size",
        ),
        (
            vec![
                "--container",
                "cylinder",
                "--radius",
                "1",
                "--count",
                "10",
                "--phi",
                "0.5",
            ],
            "--length",
        ),
        (
            vec![
                "--container",
                "box",
                "--size",
                "1,1,1",
                "--count",
                "100",
                "--phi",
                "0",
            ],
            "phi = 0",
        ),
        (
            vec![
                "--container",
                "box",
                "--size",
                "1,1,1",
                "--count",
                "100",
                "--phi",
                "0.75",
            ],
            "jams near",
        ),
        (
            vec![
                "--container",
                "box",
                "--size",
                "1,1,1",
                "--count",
                "100",
                "--phi",
                "0.5",
                "--radius-cov",
                "-0.2",
            ],
            "radius-cov",
        ),
        (
            vec![
                "--container",
                "box",
                "--size",
                "1,1,1",
                "--count",
                "1",
                "--phi",
                "0.6",
            ],
            "container too small",
        ),
        (
            vec![
                "--container",
                "tube",
                "--size",
                "1,1,1",
                "--count",
                "10",
                "--phi",
                "0.5",
            ],
            "tube",
        ),
        (
            vec![
                "--container",
                "box",
                "--size",
                "1,1,1",
                "--count",
                "10",
                "--phi",
                "0.5",
                "--bogus",
            ],
            "--bogus",
        ),
    ];
    for (extra, needle) in cases {
        let o = demcon(&base(&extra).iter().map(String::as_str).collect::<Vec<_>>());
        let t = text(&o);
        assert!(!o.status.success(), "{extra:?} succeeded: {t}");
        assert!(t.contains(needle), "{extra:?}: expected `{needle}` in: {t}");
        assert!(!t.contains("panicked"), "{t}");
        assert!(!out.exists(), "{extra:?} left a file");
    }
    assert_eq!(std::fs::read_dir(&d).unwrap().count(), 0);
    // Malformed packing file: line number.
    let bad = d.join("bad.xyzr");
    std::fs::write(&bad, "# container box 1 1 1\n0.5 0.5 0.5 0.1\n0.1 0.1 0.1\n").unwrap();
    let o = demcon(&["info", bad.to_str().unwrap()]);
    assert!(!o.status.success());
    assert!(
        text(&o).contains("bad.xyzr:3: expected 4 numbers"),
        "{}",
        text(&o)
    );
    let o = demcon(&["info", d.join("missing.xyzr").to_str().unwrap()]);
    assert!(!o.status.success() && text(&o).contains("missing.xyzr"));
    std::fs::remove_dir_all(&d).unwrap();
}
