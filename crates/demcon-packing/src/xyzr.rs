//! Plain-text packing files: one sphere per line, `x y z r` (m), with a `#` header that
//! carries the container. Files from other generators (YADE, LIGGGHTS, PackingGeneration)
//! are converted by [`crate::import_packing`] (`demcon import`).
//!
//! ```text
//! # demcon packing: one sphere per line, x y z r (m)
//! # container box 0.01 0.01 0.02
//! # count 2
//! 0.0025 0.0025 0.0025 0.0025
//! 0.0025 0.0025 0.0075 0.0025
//! ```
//! Header lines start with `#`; `# container` is one of `box LX LY LZ`, `cylinder R L`,
//! `sphere R`, `periodic LX LY LZ` (m); other `#` lines are free notes. Columns may be
//! separated by spaces, tabs or commas. Numbers are written in Rust's shortest
//! round-trip form, so a file reads back bit for bit.

use std::fmt::Write as _;
use std::io::Write as _;
use std::path::{Path, PathBuf};

use demcon_core::{Container, ParticleSet, Vec3};

use crate::error::PackingError;

/// `x` in a short form that reads back bit for bit: Rust's shortest round-trip `{}` for
/// 0 and 10⁻⁷ ≤ |x| < 10¹⁶ (so ordinary coordinates keep their usual look), else `{:e}`
/// (`1e-106`, not 105 zeros).
pub(crate) fn short(x: f64) -> String {
    let a = x.abs();
    if x == 0.0 || (1e-7..1e16).contains(&a) || !x.is_finite() {
        format!("{x}")
    } else {
        format!("{x:e}")
    }
}

/// How far a sphere may cross its container's boundary, relative to its radius
/// (dimensionless): round-off and soft-sphere imports (DEM overlaps with walls of up to ~1 %)
/// pass, a sphere outside the box does not. For a periodic box the centre may lie this far
/// outside `[0, L]`.
pub const INSIDE_TOLERANCE: f64 = 1e-2;

/// Largest volume fraction a file may claim (dimensionless): non-overlapping spheres never
/// fill more than their container.
pub const MAX_FILE_PHI: f64 = 1.0;

/// Checks that every sphere lies inside `container` within [`INSIDE_TOLERANCE`] of its
/// radius (walls: `R − wall distance ≤ tol·R`; periodic box: centre in `[−tol·R, L + tol·R]`).
/// For containers that come from elsewhere than the file (a scene, a carve).
///
/// Errors: [`PackingError::Outside`] with the first such particle and the value.
pub fn check_inside(particles: &ParticleSet, container: &Container) -> Result<(), PackingError> {
    let period = container.period();
    for (i, (c, &r)) in particles.centres.iter().zip(&particles.radii).enumerate() {
        let protrusion = match period {
            Some(l) => (0..3)
                .map(|k| (-c[k]).max(c[k] - l[k]))
                .fold(f64::NEG_INFINITY, f64::max),
            None => r - container.wall_distance(c),
        };
        if protrusion.is_nan() || protrusion > INSIDE_TOLERANCE * r {
            return Err(PackingError::Outside {
                particle: i,
                centre: [c.x, c.y, c.z],
                radius: r,
                protrusion,
                container: container_header(container),
            });
        }
    }
    Ok(())
}

/// `box 0.01 0.01 0.02` etc.: the container as in a file header.
fn container_header(c: &Container) -> String {
    match *c {
        Container::Box { size } => format!("box {} {} {}", short(size[0]), short(size[1]), short(size[2])),
        Container::Periodic { size } => format!(
            "periodic {} {} {}",
            short(size[0]),
            short(size[1]),
            short(size[2])
        ),
        Container::Cylinder { radius, length } => format!("cylinder {} {}", short(radius), short(length)),
        Container::Sphere { radius } => format!("sphere {}", short(radius)),
    }
}

/// `s` cut to 40 characters (with `…`), for echoing file text in messages.
fn clip(s: &str) -> String {
    match s.char_indices().nth(40) {
        Some((i, _)) => format!("{}…", &s[..i]),
        None => s.to_string(),
    }
}

/// A packing file's content.
#[derive(Debug, Clone, PartialEq)]
pub struct XyzrFile {
    /// The spheres (m), all of phase 0.
    pub particles: ParticleSet,
    /// Each particle's label from an optional fifth column (`x y z r label`: a material's name
    /// or index), with its line; `None` when the lines have four columns.
    pub labels: Option<Vec<(String, usize)>>,
    /// The container from the `# container` line, if any.
    pub container: Option<Container>,
    /// The other `#` lines, without the `#` and leading blanks.
    pub notes: Vec<String>,
}

/// Writes `particles` and `container` to `path` atomically (temporary file in the same
/// folder, then rename): a failure never leaves a partial file behind.
pub fn write_xyzr(path: &Path, particles: &ParticleSet, container: &Container) -> Result<(), PackingError> {
    write_xyzr_with_notes(path, particles, container, &[])
}

/// [`write_xyzr`] with extra `#` note lines after the header (e.g. provenance).
pub fn write_xyzr_with_notes(
    path: &Path,
    particles: &ParticleSet,
    container: &Container,
    notes: &[String],
) -> Result<(), PackingError> {
    write_atomic(path, format_xyzr(particles, container, notes).as_bytes())
}

/// The text of a packing file (header, notes, one `x y z r` line per sphere, m), as
/// [`write_xyzr_with_notes`] writes it. Numbers are in a short form that reads back bit
/// for bit: `{}` for 0 and 10⁻⁷ ≤ |x| < 10¹⁶, `{:e}` otherwise (`1e-106`, not 105 zeros).
pub fn format_xyzr(particles: &ParticleSet, container: &Container, notes: &[String]) -> String {
    let mut s = String::with_capacity(80 * particles.len() + 256);
    s.push_str("# demcon packing: one sphere per line, x y z r (m)\n");
    let _ = writeln!(s, "# container {}", container_header(container));
    let _ = writeln!(s, "# count {}", particles.len());
    for note in notes {
        for line in note.lines() {
            let _ = writeln!(s, "# {line}");
        }
    }
    for (c, r) in particles.centres.iter().zip(&particles.radii) {
        let _ = writeln!(s, "{} {} {} {}", short(c.x), short(c.y), short(c.z), short(*r));
    }
    s
}

/// Writes several files all or none: each to a temporary file next to it (flushed), then,
/// only if every temporary was written, renames them into place in order. On a failure the
/// temporaries are removed and no target is touched (a failed rename, e.g. a folder removed
/// meanwhile, can still leave the earlier files renamed).
pub fn write_atomic_all(files: &[(&Path, &[u8])]) -> Result<(), PackingError> {
    let mut temps: Vec<(PathBuf, &Path)> = Vec::new();
    let cleanup = |temps: &[(PathBuf, &Path)]| {
        for (t, _) in temps {
            let _ = std::fs::remove_file(t);
        }
    };
    for (path, bytes) in files {
        let tmp = temp_path(path).inspect_err(|_| cleanup(&temps))?;
        let written = (|| {
            let mut f = std::fs::File::create(&tmp)?;
            f.write_all(bytes)?;
            f.sync_all()
        })();
        if let Err(source) = written {
            let _ = std::fs::remove_file(&tmp);
            cleanup(&temps);
            return Err(PackingError::Io {
                path: path.to_path_buf(),
                source,
            });
        }
        temps.push((tmp, path));
    }
    for (k, (tmp, path)) in temps.iter().enumerate() {
        if let Err(source) = std::fs::rename(tmp, path) {
            cleanup(&temps[k..]);
            return Err(PackingError::Io {
                path: path.to_path_buf(),
                source,
            });
        }
    }
    Ok(())
}

/// Checks, before any heavy work, that `path` can be written: its folder exists and
/// accepts a new file (a probe file is created and removed), and it is not a folder.
pub fn check_writable(path: &Path) -> Result<(), PackingError> {
    let io = |kind: std::io::ErrorKind, msg: String| PackingError::Io {
        path: path.to_path_buf(),
        source: std::io::Error::new(kind, msg),
    };
    if path.is_dir() {
        return Err(io(
            std::io::ErrorKind::InvalidInput,
            "is a folder, not a file name".into(),
        ));
    }
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    if !dir.is_dir() {
        return Err(io(
            std::io::ErrorKind::NotFound,
            format!("the folder {} does not exist", dir.display()),
        ));
    }
    let probe = temp_path(path)?;
    match std::fs::File::create(&probe) {
        Ok(_) => {
            let _ = std::fs::remove_file(&probe);
            Ok(())
        }
        Err(e) => Err(io(
            e.kind(),
            format!("the folder {} is not writable: {e}", dir.display()),
        )),
    }
}

/// The temporary file next to `path` used by the atomic writers.
fn temp_path(path: &Path) -> Result<PathBuf, PackingError> {
    let name = path.file_name().ok_or_else(|| PackingError::Io {
        path: path.to_path_buf(),
        source: std::io::Error::new(std::io::ErrorKind::InvalidInput, "not a file name"),
    })?;
    let mut tmp_name = std::ffi::OsString::from(".");
    tmp_name.push(name);
    tmp_name.push(format!(".tmp{}", std::process::id()));
    Ok(path.with_file_name(tmp_name))
}

/// Writes `bytes` to a temporary file next to `path`, flushes it, and renames it over `path`.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<(), PackingError> {
    write_atomic_all(&[(path, bytes)])
}

/// Reads a packing file: the spheres and the container (if the header names one).
/// Errors give the line number and what was expected.
pub fn read_xyzr(path: &Path) -> Result<(ParticleSet, Option<Container>), PackingError> {
    let f = read_xyzr_file(path)?;
    Ok((f.particles, f.container))
}

/// Reads a packing file with its notes; see [`read_xyzr`].
pub fn read_xyzr_file(path: &Path) -> Result<XyzrFile, PackingError> {
    let text = std::fs::read_to_string(path).map_err(|source| PackingError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    parse_xyzr(&text).map_err(|(line, message)| PackingError::Parse {
        path: path.to_path_buf(),
        line,
        message,
    })
}

/// Reads only the header of a packing file (the comment lines before the first sphere): the
/// container, if it names one. Cheap on any file size, for checks before the heavy work.
pub fn read_xyzr_container(path: &Path) -> Result<Option<Container>, PackingError> {
    use std::io::BufRead;
    let io = |source| PackingError::Io {
        path: path.to_path_buf(),
        source,
    };
    let f = std::fs::File::open(path).map_err(io)?;
    for (k, raw) in std::io::BufReader::new(f).lines().enumerate() {
        let raw = raw.map_err(io)?;
        let l = raw.trim();
        if l.is_empty() {
            continue;
        }
        let Some(h) = l.strip_prefix('#') else {
            break;
        };
        if let Some(rest) = h.trim().strip_prefix("container") {
            return parse_container(rest)
                .map(Some)
                .map_err(|message| PackingError::Parse {
                    path: path.to_path_buf(),
                    line: k + 1,
                    message,
                });
        }
    }
    Ok(None)
}

/// Parses the text of a packing file; errors are `(line number, message)`.
pub fn parse_xyzr(text: &str) -> Result<XyzrFile, (usize, String)> {
    let mut centres = vec![];
    let mut radii = vec![];
    let mut container = None;
    let mut notes = vec![];
    let mut lines = vec![];
    let mut labels: Vec<(String, usize)> = vec![];
    let mut count: Option<(usize, usize)> = None;
    let mut last_line = 0;
    for (k, raw) in text.lines().enumerate() {
        let line = k + 1;
        last_line = line;
        let l = raw.trim();
        if l.is_empty() {
            continue;
        }
        if let Some(h) = l.strip_prefix('#') {
            let h = h.trim();
            if let Some(rest) = h.strip_prefix("container") {
                if container.is_some() {
                    return Err((line, "a second '# container' line".into()));
                }
                container = Some(parse_container(rest).map_err(|m| (line, m))?);
            } else if let Some(rest) = h.strip_prefix("count") {
                if count.is_some() {
                    return Err((line, "a second '# count' line".into()));
                }
                let n = rest.trim().parse::<usize>().map_err(|_| {
                    (
                        line,
                        format!(
                            "`# count {}`: expected the number of particle lines",
                            clip(rest.trim())
                        ),
                    )
                })?;
                count = Some((n, line));
            } else if !h.starts_with("demcon packing:") {
                notes.push(h.to_string());
            }
            continue;
        }
        let fields: Vec<&str> = l
            .split(|c: char| c.is_whitespace() || c == ',')
            .filter(|s| !s.is_empty())
            .collect();
        let labelled = !radii.is_empty() && !labels.is_empty() || radii.is_empty() && fields.len() == 5;
        let v = particle_line(&fields, labelled).map_err(|m| (line, m))?;
        if labelled {
            labels.push((fields[4].to_string(), line));
        }
        lines.push(line);
        centres.push(Vec3::new(v[0], v[1], v[2]));
        radii.push(v[3]);
    }
    if radii.is_empty() {
        return Err((
            last_line.max(1),
            "no particle lines (`x y z r`) in the file".into(),
        ));
    }
    if let Some((n, line)) = count
        && n != radii.len()
    {
        return Err((
            line,
            format!(
                "the header says `# count {n}` but the file has {} particle lines (truncated or edited?)",
                radii.len()
            ),
        ));
    }
    let particles = ParticleSet::new(centres, radii).map_err(|e| (last_line, e.to_string()))?;
    if let Some(c) = &container {
        check_fits(&particles, c, &lines, last_line)?;
    }
    Ok(XyzrFile {
        particles,
        labels: (!labels.is_empty()).then_some(labels),
        container,
        notes,
    })
}

/// The numbers `x y z r` of a particle line split into `fields` (with a fifth, its label, when
/// `labelled`); the error is the message for the line.
fn particle_line(fields: &[&str], labelled: bool) -> Result<[f64; 4], String> {
    let want = if labelled { 5 } else { 4 };
    if fields.len() != want {
        return Err(format!(
            "expected {} `x y z r{}` (as the first particle line), found {} fields",
            if labelled {
                "4 numbers and a label"
            } else {
                "4 numbers"
            },
            if labelled { " label" } else { "" },
            fields.len()
        ));
    }
    let mut v = [0.0; 4];
    for (q, f) in fields.iter().take(4).enumerate() {
        v[q] = f
            .parse::<f64>()
            .ok()
            .filter(|x| x.is_finite())
            .ok_or_else(|| format!("`{}` is not a finite number", clip(f)))?;
    }
    if v[3] <= 0.0 {
        return Err(format!("radius {} must be > 0", short(v[3])));
    }
    Ok(v)
}

/// Every particle inside the `# container` header's container `c`, and the spheres' volume
/// fraction possible without overlaps; the error names the particle's line (`lines`) or the
/// file's last line.
fn check_fits(
    particles: &ParticleSet,
    c: &Container,
    lines: &[usize],
    last_line: usize,
) -> Result<(), (usize, String)> {
    if let Err(e) = check_inside(particles, c) {
        let k = match e {
            PackingError::Outside { particle, .. } => particle,
            _ => 0,
        };
        return Err((lines[k], e.to_string()));
    }
    let solid: f64 =
        particles.radii.iter().map(|r| r.powi(3)).sum::<f64>() * 4.0 / 3.0 * std::f64::consts::PI;
    let phi = solid / c.volume();
    if phi.is_nan() || phi > MAX_FILE_PHI {
        return Err((
            last_line,
            format!(
                "the spheres would fill a volume fraction {} of `# container {}`, but at most \
                 {MAX_FILE_PHI} is possible without overlaps: the container is too small for these spheres",
                short(phi),
                container_header(c),
            ),
        ));
    }
    Ok(())
}

fn parse_container(rest: &str) -> Result<Container, String> {
    let words: Vec<&str> = rest.split_whitespace().collect();
    let nums = |n: usize| -> Result<Vec<f64>, String> {
        if words.len() != n + 1 {
            return Err(format!(
                "`# container {}` needs {n} numbers after the kind",
                clip(words.first().unwrap_or(&""))
            ));
        }
        words[1..]
            .iter()
            .map(|w| {
                w.parse::<f64>()
                    .map_err(|_| format!("`{}` is not a number", clip(w)))
            })
            .collect()
    };
    let c = match words.first().copied() {
        Some("box") => {
            let v = nums(3)?;
            Container::Box {
                size: [v[0], v[1], v[2]],
            }
        }
        Some("periodic") => {
            let v = nums(3)?;
            Container::Periodic {
                size: [v[0], v[1], v[2]],
            }
        }
        Some("cylinder") => {
            let v = nums(2)?;
            Container::Cylinder {
                radius: v[0],
                length: v[1],
            }
        }
        Some("sphere") => {
            let v = nums(1)?;
            Container::Sphere { radius: v[0] }
        }
        other => {
            return Err(format!(
                "unknown container `{}`: expected box, cylinder, sphere or periodic",
                clip(other.unwrap_or(""))
            ));
        }
    };
    crate::params::check_lengths(&c).map_err(|e| e.to_string())?;
    c.validate().map_err(|e| e.to_string())?;
    Ok(c)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn errors_carry_line_numbers() {
        let e = parse_xyzr("# container box 1 1 1\n0 0 0 0.1\n0 0 0.1\n").unwrap_err();
        assert_eq!(e.0, 3);
        assert!(e.1.contains("expected 4 numbers"), "{}", e.1);
        let e = parse_xyzr("0 0 0 0.1\n\n1 x 0 0.1\n").unwrap_err();
        assert_eq!(e.0, 3);
        assert!(e.1.contains("`x`"));
        let e = parse_xyzr("# container tube 1\n").unwrap_err();
        assert_eq!(e.0, 1);
        let e = parse_xyzr("1 1 1 -0.5\n").unwrap_err();
        assert!(e.1.contains("radius"));
        assert!(parse_xyzr("# nothing\n").is_err());
        let ok = parse_xyzr("# container cylinder 1 2\n# hello\n0, 0, 1, 0.5\n").unwrap();
        assert_eq!(
            ok.container,
            Some(Container::Cylinder {
                radius: 1.0,
                length: 2.0
            })
        );
        assert_eq!(ok.notes, vec!["hello".to_string()]);
    }

    #[test]
    fn a_fifth_column_labels_every_particle_or_none() {
        let f = parse_xyzr(
            "0 0 0 0.1 epoxy
1 0 0 0.1 2
",
        )
        .unwrap();
        assert_eq!(
            f.labels,
            Some(vec![("epoxy".to_string(), 1), ("2".to_string(), 2)])
        );
        assert!(
            parse_xyzr(
                "0 0 0 0.1
1 0 0 0.1
"
            )
            .unwrap()
            .labels
            .is_none()
        );
        // Mixed lines are refused at the first that differs, naming it.
        let e = parse_xyzr(
            "0 0 0 0.1 a
1 0 0 0.1
",
        )
        .unwrap_err();
        assert_eq!(e.0, 2);
        assert!(e.1.contains("label"), "{}", e.1);
        let e = parse_xyzr(
            "0 0 0 0.1
1 0 0 0.1 a
",
        )
        .unwrap_err();
        assert_eq!(e.0, 2);
    }

    /// Fuzz finding: x = 1 m in a 0.01 m box was accepted.
    #[test]
    fn reader_refuses_particles_outside_the_container() {
        let e = parse_xyzr("# container box 0.01 0.01 0.01\n0.005 0.005 0.005 0.001\n1 0.005 0.005 0.001\n")
            .unwrap_err();
        assert_eq!(e.0, 3);
        assert!(
            e.1.contains("particle 1") && e.1.contains("centre (1, 0.005, 0.005)"),
            "{}",
            e.1
        );
        // Within the tolerance (0.5 % of the radius across the wall): accepted.
        parse_xyzr("# container box 1 1 1\n0.0995 0.5 0.5 0.1\n").unwrap();
        let e = parse_xyzr("# container sphere 1\n0 0 0.95 0.1\n").unwrap_err();
        assert!(e.1.contains("outside the sphere 1"), "{}", e.1);
        let e = parse_xyzr("# container periodic 1 1 1\n0.5 0.5 1.2 0.1\n").unwrap_err();
        assert!(e.1.contains("outside the periodic"), "{}", e.1);
        // The public check for containers from elsewhere.
        let p = ParticleSet::new(vec![Vec3::new(1e297, 0.0, 0.0)], vec![0.1]).unwrap();
        let e = check_inside(&p, &Container::Box { size: [1.0; 3] })
            .unwrap_err()
            .to_string();
        assert!(e.contains("1e297") && e.len() < 400, "{e}");
    }

    /// Fuzz finding: a truncated file passed although its header gave the count.
    #[test]
    fn reader_checks_the_count_header() {
        let e =
            parse_xyzr("# container box 1 1 1\n# count 3\n0.5 0.5 0.5 0.1\n0.2 0.2 0.2 0.1\n").unwrap_err();
        assert_eq!(e.0, 2);
        assert!(
            e.1.contains("`# count 3`") && e.1.contains("2 particle lines"),
            "{}",
            e.1
        );
        assert!(
            parse_xyzr("# count many\n0 0 0 1\n")
                .unwrap_err()
                .1
                .contains("count many")
        );
        parse_xyzr("# count 1\n0 0 0 1\n").unwrap();
    }

    /// Fuzz finding: `info` printed φ = 550 for a header box far too small.
    #[test]
    fn reader_refuses_impossible_volume_fractions() {
        let mut text = String::from("# container periodic 1 1 1\n");
        for k in 0..20 {
            text.push_str(&format!("0.5 0.5 {} 0.4\n", k as f64 / 20.0));
        }
        let e = parse_xyzr(&text).unwrap_err();
        assert!(
            e.1.contains("volume fraction 5.36") && e.1.contains("at most 1"),
            "{}",
            e.1
        );
    }

    /// Fuzz finding: a radius of 1e-106 was written as 105 zeros. Numbers stay short and
    /// read back bit for bit.
    #[test]
    fn writer_writes_short_round_trip_numbers() {
        let values = [
            1e-106,
            0.0025,
            0.1 + 0.2,
            1e300,
            123456.789,
            1.0,
            5e-324,
            1e-7,
            9.99e15,
            1e16,
        ];
        for &v in &values {
            let t = short(v);
            assert!(t.len() <= 25, "{t}");
            assert_eq!(t.parse::<f64>().unwrap().to_bits(), v.to_bits(), "{t}");
        }
        assert_eq!(short(1e-106), "1e-106");
        assert_eq!(short(0.0025), "0.0025");
        let p = ParticleSet::new(vec![Vec3::new(1e-106, 0.5, 0.25)], vec![1e-106]).unwrap();
        let text = format_xyzr(&p, &Container::Box { size: [1.0; 3] }, &[]);
        assert!(text.contains("1e-106 0.5 0.25 1e-106"), "{text}");
        assert!(text.len() < 200);
        let back = parse_xyzr(&text).unwrap();
        assert_eq!(back.particles, p);
    }
}
