//! `cargo xtask fuzz [--runs N] [--seed S] [--timeout SECS] [--out DIR]`: a fuzz campaign of
//! the `demcon` binary. Each case mutates an input at random — an example scene (its particle
//! count capped so a case runs in about a second), a packing file, a periodic packing file and
//! the repeat counts of `tile`, or the flags of `pack` —
//! and runs the release binary on it with a time limit, two cases at a time. The summary
//! counts, beside the clean errors and the successes:
//! - panics (exit code 101 or "panicked" on stderr) and deaths by a signal (e.g. the
//!   system's out-of-memory killer),
//! - hangs (killed at the time limit),
//! - non-finite outputs (a successful run whose outputs hold NaN/inf, or a null where a
//!   number belongs in `summary.json`),
//! - outputs left behind by a failed run;
//! - error messages that name a Rust type (`SceneConfig`, `RegionConfig::Difference`) instead
//!   of a scene field, or say one file path twice.
//!
//! Each offending input is kept under `<out>/failures/` with the command that ran it. The
//! campaign is deterministic for a seed (the mutations, not the timings).
//!
//! `cargo xtask fuzz --metamorphic [--runs N]` runs instead the metamorphic suite
//! (`crates/demcon-scene/tests/metamorphic.rs`: invariances the physics guarantees, on random
//! small scenes) with N random cases per property (default 200) in release mode.

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::sync::Mutex;
use std::time::{Duration, Instant};

use anyhow::{Context, Result, bail};

/// SplitMix64: a small seeded generator for the mutations.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }
    fn below(&mut self, n: usize) -> usize {
        (self.next() % n.max(1) as u64) as usize
    }
}

/// Values that broke earlier versions: zero, negative, huge, tiny, subnormal, non-finite.
const EXTREMES: &[&str] = &[
    "0",
    "0.0",
    "-1.0",
    "1e308",
    "1e-308",
    "4.9e-324",
    "NaN",
    "inf",
    "-inf",
    "18446744073709551615",
    "1e-70",
    "7.5e-30",
    "4294967296",
    "1e-300",
    "0.5",
    "1",
    "2",
];

/// What one case runs.
struct Case {
    /// Files to write into the case folder: (name, contents).
    files: Vec<(String, Vec<u8>)>,
    /// Arguments of `demcon` (the case folder replaces `{dir}`).
    args: Vec<String>,
}

/// Outcome of one case.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Outcome {
    Ok,
    CleanError,
    Panic,
    Hang,
    NonFinite,
    LeftOutput,
    TypeName,
    RepeatedPath,
}

/// Runs the campaign.
pub fn run(rest: &[String]) -> Result<()> {
    if rest.iter().any(|a| a == "--metamorphic") {
        return metamorphic(rest);
    }
    let mut runs = 500usize;
    let mut seed = 1u64;
    let mut timeout = 30.0f64;
    let mut out = PathBuf::from("target/fuzz");
    let mut it = rest.iter();
    while let Some(a) = it.next() {
        let mut val = || it.next().with_context(|| format!("{a} needs a value"));
        match a.as_str() {
            "--runs" => runs = val()?.parse().context("--runs: a count")?,
            "--seed" => seed = val()?.parse().context("--seed: an integer")?,
            "--timeout" => timeout = val()?.parse().context("--timeout: seconds")?,
            "--out" => out = PathBuf::from(val()?),
            other => bail!("unknown fuzz option `{other}` (--runs N, --seed S, --timeout SECS, --out DIR)"),
        }
    }
    if runs == 0 || timeout.is_nan() || timeout <= 0.0 {
        bail!("--runs must be ≥ 1 and --timeout > 0 s");
    }
    crate::run(crate::cargo().args(["build", "--release", "-q", "-p", "demcon"]))?;
    let target = std::env::var_os("CARGO_TARGET_DIR").map_or_else(|| PathBuf::from("target"), PathBuf::from);
    let bin = std::fs::canonicalize(target.join("release/demcon")).context("the release demcon binary")?;
    let _ = std::fs::remove_dir_all(&out);
    std::fs::create_dir_all(out.join("failures"))?;
    let out = std::fs::canonicalize(&out)?;
    let corpus = corpus(&bin, &out)?;
    let mut rng = Rng(seed);
    let cases: Vec<Case> = (0..runs).map(|_| mutate(&corpus, &mut rng)).collect();
    let counts = Mutex::new([0usize; 8]);
    let next = Mutex::new(0usize);
    let start = Instant::now();
    std::thread::scope(|s| {
        for _ in 0..2 {
            s.spawn(|| {
                loop {
                    let k = {
                        let mut n = next.lock().unwrap();
                        let k = *n;
                        *n += 1;
                        k
                    };
                    if k >= cases.len() {
                        break;
                    }
                    let o = run_case(&bin, &out, k, &cases[k], timeout);
                    counts.lock().unwrap()[o as usize] += 1;
                    if (k + 1) % 100 == 0 {
                        eprintln!(
                            "fuzz: {} / {} cases ({:.0} s)",
                            k + 1,
                            runs,
                            start.elapsed().as_secs_f64()
                        );
                    }
                }
            });
        }
    });
    let c = counts.into_inner().unwrap();
    let summary = format!(
        "fuzz: {runs} cases (seed {seed}, timeout {timeout} s) in {:.0} s: {} ran, {} clean errors; \
         panics or signals {}, hangs {}, non-finite outputs {}, outputs left by failed runs {}, messages naming \
         a Rust type {}, messages saying a path twice {}",
        start.elapsed().as_secs_f64(),
        c[Outcome::Ok as usize],
        c[Outcome::CleanError as usize],
        c[Outcome::Panic as usize],
        c[Outcome::Hang as usize],
        c[Outcome::NonFinite as usize],
        c[Outcome::LeftOutput as usize],
        c[Outcome::TypeName as usize],
        c[Outcome::RepeatedPath as usize],
    );
    println!("{summary}");
    std::fs::write(out.join("summary.txt"), format!("{summary}\n"))?;
    let bad = c[Outcome::Panic as usize]
        + c[Outcome::Hang as usize]
        + c[Outcome::NonFinite as usize]
        + c[Outcome::LeftOutput as usize]
        + c[Outcome::TypeName as usize]
        + c[Outcome::RepeatedPath as usize];
    if bad > 0 {
        bail!("{bad} failing cases, kept in {}", out.join("failures").display());
    }
    Ok(())
}

/// The inputs mutations start from: the example scenes (particle counts capped at 400,
/// no VTK) and two small packing files written by `demcon pack`, in a box and periodic.
struct Corpus {
    scenes: Vec<(String, String)>,
    packing: String,
    periodic: String,
}

fn corpus(bin: &Path, out: &Path) -> Result<Corpus> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes");
    let mut scenes = Vec::new();
    for e in std::fs::read_dir(&dir)? {
        let p = e?.path();
        if p.extension().and_then(|x| x.to_str()) != Some("ron") {
            continue;
        }
        let text = std::fs::read_to_string(&p)?;
        scenes.push((
            p.file_name().unwrap().to_string_lossy().into_owned(),
            cap_count(&text, 400),
        ));
    }
    scenes.sort();
    let packing = |container: &str| -> Result<String> {
        let pk = out.join(format!("corpus-{container}.xyzr"));
        let status = Command::new(bin)
            .args(["pack", "--container", container, "--size", "0.01,0.01,0.01"])
            .args(["--count", "300", "--phi", "0.55", "--seed", "3", "--out"])
            .arg(&pk)
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .status()?;
        if !status.success() {
            bail!("could not write the corpus packing ({container})");
        }
        Ok(std::fs::read_to_string(&pk)?)
    };
    Ok(Corpus {
        scenes,
        packing: packing("box")?,
        periodic: packing("periodic")?,
    })
}

/// `text` with every `count: N` above `max` set to `max`.
fn cap_count(text: &str, max: usize) -> String {
    let mut out = String::new();
    let mut rest = text;
    while let Some(i) = rest.find("count: ") {
        let (head, tail) = rest.split_at(i + 7);
        out.push_str(head);
        let digits: String = tail
            .chars()
            .take_while(|c| c.is_ascii_digit() || *c == '_')
            .collect();
        match digits.replace('_', "").parse::<usize>() {
            Ok(n) if n > max => out.push_str(&max.to_string()),
            _ => out.push_str(&digits),
        }
        rest = &tail[digits.len()..];
    }
    out.push_str(rest);
    out.replace("vtk: true", "vtk: false")
}

/// The byte spans of the numbers in `text`.
fn numbers(text: &str) -> Vec<(usize, usize)> {
    let b = text.as_bytes();
    let mut spans = Vec::new();
    let mut i = 0;
    while i < b.len() {
        if b[i].is_ascii_digit() && (i == 0 || !b[i - 1].is_ascii_alphanumeric()) {
            let s = i;
            while i < b.len() && (b[i].is_ascii_digit() || b".e-+_".contains(&b[i])) {
                i += 1;
            }
            spans.push((s, i));
        } else {
            i += 1;
        }
    }
    spans
}

/// 1–3 random edits of `text`: a number replaced by an extreme value (most often), a byte
/// range cut, or a line duplicated.
fn edit(text: &str, rng: &mut Rng) -> Vec<u8> {
    let mut t = text.as_bytes().to_vec();
    for _ in 0..1 + rng.below(3) {
        let s = String::from_utf8_lossy(&t).into_owned();
        match rng.below(10) {
            0 => {
                let a = rng.below(t.len());
                let b = (a + 1 + rng.below(30)).min(t.len());
                t.drain(a..b);
            }
            1 => {
                let lines: Vec<&str> = s.lines().collect();
                let k = rng.below(lines.len());
                let mut v: Vec<String> = lines.iter().map(|l| l.to_string()).collect();
                v.insert(k, lines[k].to_string());
                t = v.join("\n").into_bytes();
            }
            _ => {
                let spans = numbers(&s);
                if spans.is_empty() {
                    continue;
                }
                let (a, b) = spans[rng.below(spans.len())];
                let v = EXTREMES[rng.below(EXTREMES.len())];
                t = format!("{}{v}{}", &s[..a], &s[b..]).into_bytes();
            }
        }
    }
    t
}

fn mutate(c: &Corpus, rng: &mut Rng) -> Case {
    let s = |v: &[&str]| v.iter().map(|x| x.to_string()).collect::<Vec<_>>();
    match rng.below(10) {
        // A mutated example scene.
        0..=5 => {
            let (name, text) = &c.scenes[rng.below(c.scenes.len())];
            Case {
                files: vec![(name.clone(), edit(text, rng))],
                args: vec![
                    "run".into(),
                    format!("{{dir}}/{name}"),
                    "--out".into(),
                    "{dir}/out".into(),
                ]
                .into_iter()
                .chain(s(&["--quiet", "--threads", "1"]))
                .collect(),
            }
        }
        // A mutated packing file, read by `info` or run by a steady scene.
        6 | 7 => {
            let file = edit(&c.packing, rng);
            if rng.below(2) == 0 {
                Case {
                    files: vec![("p.xyzr".into(), file)],
                    args: s(&["info", "{dir}/p.xyzr"]),
                }
            } else {
                let scene = "(packing: File(path: \"p.xyzr\"), surface: TerrerosAlpha,\n\
                     materials: [(name: \"m\", conductivity: 1.0, density: 1.0, specific_heat: 1.0)],\n\
                     thermal: (bcs: [WallTemperature(face: XMin, value: 0.0), WallTemperature(face: XMax, value: 1.0)],\n\
                     solver: Steady), outputs: (etc_axis: Some(X), vtk: false))";
                Case {
                    files: vec![
                        ("p.xyzr".into(), file),
                        ("s.ron".into(), scene.as_bytes().to_vec()),
                    ],
                    args: s(&[
                        "run",
                        "{dir}/s.ron",
                        "--out",
                        "{dir}/out",
                        "--quiet",
                        "--threads",
                        "1",
                    ]),
                }
            }
        }
        // `tile` of the periodic packing file, mutated or not, each repeat count a small one
        // or an extreme value.
        8 => {
            let file = if rng.below(2) == 0 {
                edit(&c.periodic, rng)
            } else {
                c.periodic.clone().into_bytes()
            };
            // 3000 along two axes or more asks for ≥ 2.7·10⁹ particles: within the 32-bit
            // ids, beyond any machine's memory (to be refused with the estimate).
            let repeat: Vec<String> = (0..3)
                .map(|_| match rng.below(6) {
                    0 | 1 => EXTREMES[rng.below(EXTREMES.len())].to_string(),
                    2 => "3000".to_string(),
                    _ => (1 + rng.below(3)).to_string(),
                })
                .collect();
            Case {
                files: vec![("p.xyzr".into(), file)],
                args: s(&[
                    "tile",
                    "{dir}/p.xyzr",
                    "--repeat",
                    &repeat.join(","),
                    "--out",
                    "{dir}/t.xyzr",
                ]),
            }
        }
        // `pack` with one flag set to an extreme value.
        _ => {
            let mut args = s(&[
                "pack",
                "--container",
                "box",
                "--size",
                "0.01,0.01,0.01",
                "--count",
                "200",
                "--phi",
                "0.5",
                "--seed",
                "1",
                "--out",
                "{dir}/p.xyzr",
            ]);
            let flags = [
                "--count",
                "--phi",
                "--radius-cov",
                "--growth-rate",
                "--neighbour-skin",
                "--max-events",
                "--max-time",
                "--threads",
            ];
            let f = flags[rng.below(flags.len())];
            let v = EXTREMES[rng.below(EXTREMES.len())];
            match args.iter().position(|a| a == f) {
                Some(i) => args[i + 1] = v.into(),
                None => args.extend([f.to_string(), v.to_string()]),
            }
            Case { files: vec![], args }
        }
    }
}

fn run_case(bin: &Path, out: &Path, k: usize, case: &Case, timeout: f64) -> Outcome {
    let dir = out.join(format!("case-{k}"));
    let _ = std::fs::remove_dir_all(&dir);
    if std::fs::create_dir_all(&dir).is_err() {
        return Outcome::CleanError;
    }
    for (name, bytes) in &case.files {
        let _ = std::fs::write(dir.join(name), bytes);
    }
    let args: Vec<String> = case
        .args
        .iter()
        .map(|a| a.replace("{dir}", &dir.to_string_lossy()))
        .collect();
    let outcome = execute(bin, &args, &dir, timeout);
    if outcome != Outcome::Ok && outcome != Outcome::CleanError {
        let keep = out.join("failures").join(format!("case-{k}-{outcome:?}"));
        let _ = std::fs::rename(&dir, &keep);
        let _ = std::fs::write(keep.join("command.txt"), args.join(" "));
    } else {
        let _ = std::fs::remove_dir_all(&dir);
    }
    outcome
}

fn execute(bin: &Path, args: &[String], dir: &Path, timeout: f64) -> Outcome {
    let Ok(mut child) = Command::new(bin)
        .args(args)
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
    else {
        return Outcome::CleanError;
    };
    let start = Instant::now();
    let status = loop {
        match child.try_wait() {
            Ok(Some(s)) => break s,
            Ok(None) if start.elapsed().as_secs_f64() > timeout => {
                let _ = child.kill();
                let _ = child.wait();
                return Outcome::Hang;
            }
            Ok(None) => std::thread::sleep(Duration::from_millis(20)),
            Err(_) => return Outcome::CleanError,
        }
    };
    let mut err = String::new();
    if let Some(mut e) = child.stderr.take() {
        use std::io::Read;
        let _ = e.read_to_string(&mut err);
    }
    // A panic, or a death by a signal this harness did not send (the system's out-of-memory
    // killer, a crash): counted together.
    if status.code() == Some(101) || status.code().is_none() || err.contains("panicked") {
        return Outcome::Panic;
    }
    let outputs: Vec<PathBuf> = ["out", "p.xyzr", "t.xyzr"]
        .iter()
        .map(|f| dir.join(f))
        .filter(|p| p.exists())
        .collect();
    if status.code() == Some(3) {
        // `pack` stopped short of its target: the packing is written on purpose, with the
        // reason on stderr and this exit code.
        return Outcome::CleanError;
    }
    if !status.success() {
        // A failed run leaves no output folder, a failed `pack` or `tile` no packing file.
        let left = dir.join("out").exists()
            || (args[0] == "pack" && dir.join("p.xyzr").exists())
            || dir.join("t.xyzr").exists();
        return if left {
            Outcome::LeftOutput
        } else if names_a_type(&err) {
            Outcome::TypeName
        } else if says_a_path_twice(&err) {
            Outcome::RepeatedPath
        } else {
            Outcome::CleanError
        };
    }
    for o in outputs {
        if non_finite(&o) {
            return Outcome::NonFinite;
        }
    }
    Outcome::Ok
}

/// Whether a message names a Rust type of the scene schema (`…Config`, or a `Type::Variant`
/// path) where a user should read a scene field.
fn names_a_type(message: &str) -> bool {
    message
        .split(|c: char| !(c.is_alphanumeric() || c == '_' || c == ':'))
        .any(|w| {
            (w.len() > 6 && w.ends_with("Config") && w.starts_with(char::is_uppercase)) || w.contains("::")
        })
}

/// Whether a line of a message says one file path twice (`reading p.xyzr: p.xyzr:3: …`).
fn says_a_path_twice(message: &str) -> bool {
    message.lines().any(|line| {
        let paths: Vec<&str> = line
            .split_whitespace()
            .map(|w| w.trim_end_matches(':').split(':').next().unwrap_or(""))
            .filter(|w| w.len() > 1 && w.contains('.') && w.parse::<f64>().is_err() && !w.starts_with('`'))
            .filter(|w| w.contains('/') || w.ends_with(".ron") || w.ends_with(".xyzr") || w.ends_with(".txt"))
            .collect();
        paths.iter().enumerate().any(|(i, p)| paths[..i].contains(p))
    })
}

/// Whether an output (a file or a folder of files) holds a non-finite number.
fn non_finite(path: &Path) -> bool {
    let files: Vec<PathBuf> = if path.is_dir() {
        std::fs::read_dir(path)
            .map(|d| d.filter_map(|e| e.ok().map(|e| e.path())).collect())
            .unwrap_or_default()
    } else {
        vec![path.to_path_buf()]
    };
    files.iter().any(|f| {
        let Ok(t) = std::fs::read_to_string(f) else {
            return false;
        };
        let lower = t.to_ascii_lowercase();
        let csv_bad = lower.contains(",nan") || lower.contains(",inf") || lower.contains(",-inf");
        // A packing file: every number of a data line finite.
        let xyzr_bad = f.extension().and_then(|e| e.to_str()) == Some("xyzr")
            && t.lines().filter(|l| !l.starts_with('#')).any(|l| {
                l.split_whitespace()
                    .any(|w| w.parse::<f64>().is_ok_and(|v| !v.is_finite()))
            });
        let json_bad = f.extension().and_then(|e| e.to_str()) == Some("json")
            && [
                "\"value\": null",
                "\"lambda_e\": null",
                "\"heat_flow_w\": null",
                "\"phi\": null",
            ]
            .iter()
            .any(|k| t.contains(k));
        csv_bad || json_bad || xyzr_bad
    })
}

/// `--metamorphic [--runs N]`: the metamorphic suite with N random cases per property.
fn metamorphic(rest: &[String]) -> Result<()> {
    let mut runs = 200u32;
    let mut it = rest.iter().filter(|a| *a != "--metamorphic");
    while let Some(a) = it.next() {
        match a.as_str() {
            "--runs" => {
                runs = it
                    .next()
                    .context("--runs needs a value")?
                    .parse()
                    .context("--runs: a count")?
            }
            other => bail!("unknown option `{other}` with --metamorphic (--runs N)"),
        }
    }
    if runs == 0 {
        bail!("--runs must be ≥ 1");
    }
    let start = Instant::now();
    crate::run(
        crate::cargo()
            .args([
                "test",
                "--release",
                "-q",
                "-p",
                "demcon-scene",
                "--test",
                "metamorphic",
            ])
            .env("DEMCON_METAMORPHIC_CASES", runs.to_string()),
    )?;
    println!(
        "metamorphic suite: {runs} random cases per property, all held ({:.0} s)",
        start.elapsed().as_secs_f64()
    );
    Ok(())
}
