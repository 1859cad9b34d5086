//! End-to-end tests of `demcon import` and of `demcon info --container`: a YADE file and a
//! PackingGeneration folder written here, imported and read back; bad input fails with a
//! message naming the file and what is missing, and leaves no output file.

mod common;

use common::{demcon, scratch, text};

/// Three spheres of radius 0.1 in the unit cube, YADE's `export.text` layout.
const YADE: &str = "#format x_y_z_r\n0.25\t0.25\t0.25\t0.1\n0.75\t0.25\t0.5\t0.1\n0.5\t0.75\t0.75\t0.1\n";

#[test]
fn yade_import_with_container_then_info() {
    let d = scratch("import", "yade");
    let src = d.join("export.txt");
    std::fs::write(&src, YADE).unwrap();
    let out = d.join("p.xyzr");
    let o = demcon(&[
        "import",
        "--from",
        "yade-text",
        src.to_str().unwrap(),
        "--container",
        "box",
        "--size",
        "1,1,1",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", text(&o));
    let written = std::fs::read_to_string(&out).unwrap();
    assert!(written.contains("# container box 1 1 1"), "{written}");
    assert!(
        written.contains("(yade-text)") && written.contains("export.txt"),
        "{written}"
    );
    assert!(written.contains("0.75 0.25 0.5 0.1"), "{written}");
    let o = demcon(&["info", out.to_str().unwrap()]);
    assert!(o.status.success(), "{}", text(&o));
    assert!(text(&o).contains("volume fraction"), "{}", text(&o));
}

#[test]
fn yade_import_without_container_fails_before_writing() {
    let d = scratch("import", "yade-bad");
    let src = d.join("export.txt");
    std::fs::write(&src, YADE).unwrap();
    let out = d.join("p.xyzr");
    let o = demcon(&[
        "import",
        "--from",
        "yade-text",
        src.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    let t = text(&o);
    assert!(!o.status.success());
    assert!(
        t.contains("export.txt") && t.contains("gives no container") && t.contains("--container"),
        "{t}"
    );
    assert!(!out.exists());
    // Too small: the spheres stick out; the check_inside error, nothing written.
    let o = demcon(&[
        "import",
        "--from",
        "yade-text",
        src.to_str().unwrap(),
        "--container",
        "box",
        "--size",
        "0.5,1,1",
        "--out",
        out.to_str().unwrap(),
    ]);
    let t = text(&o);
    assert!(!o.status.success());
    assert!(
        t.contains("do not fit") && t.contains("lies outside the box 0.5 1 1"),
        "{t}"
    );
    assert!(!out.exists());
}

#[test]
fn unknown_format_and_missing_nfo_are_clear_errors() {
    let d = scratch("import", "unknown");
    let out = d.join("p.xyzr");
    let o = demcon(&[
        "import",
        "--from",
        "lammps-binary",
        d.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    let t = text(&o);
    assert!(!o.status.success());
    assert!(
        t.contains("lammps-binary") && t.contains("packinggeneration"),
        "{t}"
    );
    std::fs::write(d.join("packing.xyzd"), [0u8; 64]).unwrap();
    let o = demcon(&[
        "import",
        "--from",
        "packinggeneration",
        d.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    let t = text(&o);
    assert!(!o.status.success());
    assert!(t.contains("packing.nfo") && t.contains("missing"), "{t}");
    assert!(!out.exists());
}

#[test]
fn info_with_container_flags_gives_phi_of_a_bare_file() {
    let d = scratch("import", "info");
    let f = d.join("bare.xyzr");
    std::fs::write(&f, "0.25 0.25 0.25 0.1\n0.75 0.75 0.75 0.1\n").unwrap();
    let o = demcon(&["info", f.to_str().unwrap()]);
    assert!(text(&o).contains("volume fraction unknown"), "{}", text(&o));
    let o = demcon(&[
        "info",
        f.to_str().unwrap(),
        "--container",
        "box",
        "--size",
        "1,1,1",
    ]);
    let t = text(&o);
    assert!(o.status.success(), "{t}");
    // 2 · 4/3 π 0.1³ = 0.0083776 in a unit box.
    assert!(t.contains("volume fraction    0.00838"), "{t}");
    let o = demcon(&["info", f.to_str().unwrap(), "--container", "box"]);
    assert!(
        !o.status.success() && text(&o).contains("needs --size"),
        "{}",
        text(&o)
    );
}

#[test]
fn spheres_overlapping_past_what_the_cells_accept_exit_non_zero() {
    // Two spheres of radius 0.1 whose centres are 0.02 apart: an overlap of 1.8 radii (as a
    // file in mm read as m, or a compressed soft-sphere state would have).
    let d = scratch("import", "overlap");
    let src = d.join("export.txt");
    std::fs::write(&src, "#format x_y_z_r\n0.5\t0.5\t0.5\t0.1\n0.52\t0.5\t0.5\t0.1\n").unwrap();
    let out = d.join("p.xyzr");
    let args = |extra: &[&'static str]| {
        let mut a = vec![
            "import",
            "--from",
            "yade-text",
            src.to_str().unwrap(),
            "--container",
            "box",
        ];
        a.extend(["--size", "1,1,1", "--out", out.to_str().unwrap()]);
        a.extend(extra);
        a.into_iter().map(String::from).collect::<Vec<_>>()
    };
    let run = |a: Vec<String>| demcon(&a.iter().map(String::as_str).collect::<Vec<_>>());
    let o = run(args(&[]));
    let t = text(&o);
    assert_eq!(o.status.code(), Some(4), "{t}");
    assert!(
        t.contains("1.800 × the smaller radius") && t.contains("--allow-overlap"),
        "{t}"
    );
    assert!(out.exists(), "the file is written all the same");
    let o = run(args(&["--allow-overlap"]));
    assert!(o.status.success(), "{}", text(&o));
    assert!(text(&o).contains("warning"), "{}", text(&o));
}
