//! Packings written by other DEM codes, read into demcon spheres and a container:
//! PackingGeneration (V. Baranau: a folder with `packing.xyzd`, `packing.nfo`,
//! `generation.conf`), a LIGGGHTS/LAMMPS `dump custom` text file (its last snapshot), and
//! YADE's `export.text` (`#format x_y_z_r`). Each reader returns an [`ImportedPacking`];
//! [`check_imported`] applies the checks every demcon packing file passes (every sphere
//! inside the container, φ ≤ 1) to the container finally used.
//!
//! PackingGeneration keeps the diameters of its input in `packing.xyzd`; the true diameters
//! are `d · ((1 − final porosity) / (1 − theoretical porosity))^(1/3)` with both porosities
//! from `packing.nfo` (its README, "Note on final diameters").

use std::path::Path;

use demcon_core::{Container, ParticleSet, Vec3};

use crate::error::PackingError;
use crate::xyzr::{MAX_FILE_PHI, check_inside, short};

/// Bytes of one PackingGeneration record: x, y, z, d as little-endian f64.
pub const PACKING_GENERATION_RECORD_BYTES: usize = 32;

/// The formats [`import_packing`] reads.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ImportFormat {
    /// PackingGeneration (Baranau): a folder with `packing.xyzd` (x y z d, little-endian
    /// f64), `packing.nfo` (porosities) and `generation.conf` (box size, boundaries).
    PackingGeneration,
    /// LIGGGHTS/LAMMPS `dump custom` text with `x y z radius` columns (last snapshot).
    LiggghtsDump,
    /// YADE `export.text`: `#format x_y_z_r`, then `x y z r` per line (no container).
    YadeText,
}

impl ImportFormat {
    /// The name used on the command line and in notes.
    pub fn name(self) -> &'static str {
        match self {
            ImportFormat::PackingGeneration => "packinggeneration",
            ImportFormat::LiggghtsDump => "liggghts-dump",
            ImportFormat::YadeText => "yade-text",
        }
    }
}

/// A packing read from another code.
#[derive(Debug, Clone, PartialEq)]
pub struct ImportedPacking {
    /// The spheres (m, in the source's units), all of phase 0.
    pub particles: ParticleSet,
    /// The container the source file gives, if any.
    pub container: Option<Container>,
    /// What was done on the way (rescaling, shift, wrapping), for `#` notes.
    pub notes: Vec<String>,
}

/// Reads `path` (a folder for [`ImportFormat::PackingGeneration`], else a file).
///
/// Errors: [`PackingError::Import`] naming the file and what is missing,
/// [`PackingError::Parse`] with the line of a malformed text line, [`PackingError::Io`].
pub fn import_packing(format: ImportFormat, path: &Path) -> Result<ImportedPacking, PackingError> {
    match format {
        ImportFormat::PackingGeneration => read_packing_generation(path),
        ImportFormat::LiggghtsDump => read_liggghts_dump(path),
        ImportFormat::YadeText => read_yade_text(path),
    }
}

/// Checks the imported spheres against the container finally used, as a packing file is
/// checked when read: every sphere inside ([`check_inside`]) and a volume fraction ≤ 1.
pub fn check_imported(particles: &ParticleSet, container: &Container) -> Result<(), PackingError> {
    container.validate()?;
    check_inside(particles, container)?;
    let phi = particles.solid_volume() / container.volume();
    if phi.is_nan() || phi > MAX_FILE_PHI {
        return Err(PackingError::ContainerTooSmall {
            reason: format!(
                "the spheres would fill a volume fraction {} of the container, at most {MAX_FILE_PHI} is possible",
                short(phi)
            ),
        });
    }
    Ok(())
}

fn import_err(path: &Path, message: impl Into<String>) -> PackingError {
    PackingError::Import {
        path: path.to_path_buf(),
        message: message.into(),
    }
}

/// Reads a file, turning "not found" into an [`PackingError::Import`] saying what the file is.
fn read_required(path: &Path, what: &str) -> Result<Vec<u8>, PackingError> {
    std::fs::read(path).map_err(|source| {
        if source.kind() == std::io::ErrorKind::NotFound {
            import_err(path, format!("missing: {what}"))
        } else {
            PackingError::Io {
                path: path.to_path_buf(),
                source,
            }
        }
    })
}

fn read_text(path: &Path, what: &str) -> Result<String, PackingError> {
    String::from_utf8(read_required(path, what)?)
        .map_err(|_| import_err(path, format!("not a text file (expected {what})")))
}

fn particle_set(path: &Path, centres: Vec<Vec3>, radii: Vec<f64>) -> Result<ParticleSet, PackingError> {
    if radii.is_empty() {
        return Err(import_err(path, "no particles in the file"));
    }
    ParticleSet::new(centres, radii).map_err(|e| import_err(path, e.to_string()))
}

/// The value after `key` on the first line (trimmed) starting with it.
fn keyed<'a>(text: &'a str, key: &str) -> Option<&'a str> {
    text.lines()
        .find_map(|l| l.trim().strip_prefix(key))
        .map(str::trim)
}

/// Reads a PackingGeneration folder: `packing.xyzd` (required), `packing.nfo` (required: the
/// porosities that rescale the diameters) and `generation.conf` (optional: the box size and
/// boundaries mode; without it the container must come from elsewhere).
pub fn read_packing_generation(dir: &Path) -> Result<ImportedPacking, PackingError> {
    if !dir.is_dir() {
        return Err(import_err(
            dir,
            "not a folder: give the PackingGeneration folder holding packing.xyzd, packing.nfo and generation.conf",
        ));
    }
    let xyzd = dir.join("packing.xyzd");
    let nfo = dir.join("packing.nfo");
    let conf = dir.join("generation.conf");
    let bytes = read_required(
        &xyzd,
        "the packing file packing.xyzd (x y z d, little-endian f64)",
    )?;
    if bytes.is_empty() || bytes.len() % PACKING_GENERATION_RECORD_BYTES != 0 {
        return Err(import_err(
            &xyzd,
            format!(
                "{} bytes is not a whole, non-zero number of {PACKING_GENERATION_RECORD_BYTES}-byte records \
                 (x y z d as little-endian f64): truncated or not a PackingGeneration packing",
                bytes.len()
            ),
        ));
    }
    let info = read_text(
        &nfo,
        "packing.nfo (PackingGeneration writes it after a successful generation; its porosities rescale the diameters)",
    )?;
    let porosity = |key: &str| -> Result<f64, PackingError> {
        let v = keyed(&info, key).ok_or_else(|| import_err(&nfo, format!("no `{key}` line")))?;
        v.split_whitespace()
            .next()
            .and_then(|w| w.parse::<f64>().ok())
            .filter(|p| (0.0..1.0).contains(p))
            .ok_or_else(|| import_err(&nfo, format!("`{key} {v}`: expected a porosity in [0, 1)")))
    };
    let theoretical = porosity("Theoretical Porosity:")?;
    let final_porosity = porosity("Final Porosity:")?;
    let factor = ((1.0 - final_porosity) / (1.0 - theoretical)).cbrt();
    let n = bytes.len() / PACKING_GENERATION_RECORD_BYTES;
    if let Some(v) = keyed(&info, "N:") {
        match v.parse::<usize>() {
            Ok(m) if m == n => {}
            _ => {
                return Err(import_err(
                    &nfo,
                    format!("says `N: {v}` but packing.xyzd holds {n} records"),
                ));
            }
        }
    }
    let mut centres = Vec::with_capacity(n);
    let mut radii = Vec::with_capacity(n);
    for (i, rec) in bytes.chunks_exact(PACKING_GENERATION_RECORD_BYTES).enumerate() {
        let v: [f64; 4] =
            std::array::from_fn(|k| f64::from_le_bytes(rec[8 * k..8 * k + 8].try_into().expect("8 bytes")));
        if !v.iter().all(|x| x.is_finite()) || v[3] <= 0.0 {
            return Err(import_err(
                &xyzd,
                format!(
                    "record {i} (x y z d = {} {} {} {}): expected finite numbers and a diameter > 0",
                    short(v[0]),
                    short(v[1]),
                    short(v[2]),
                    short(v[3])
                ),
            ));
        }
        centres.push(Vec3::new(v[0], v[1], v[2]));
        radii.push(0.5 * v[3] * factor);
    }
    let particles = particle_set(&xyzd, centres, radii)?;
    let mut notes = vec![format!(
        "diameters of packing.xyzd scaled by ((1 - {final_porosity}) / (1 - {theoretical}))^(1/3) = {} (packing.nfo)",
        short(factor)
    )];
    let container = if conf.exists() {
        let text = read_text(&conf, "generation.conf")?;
        let size: Vec<f64> = keyed(&text, "Packing size:")
            .map(|v| v.split_whitespace().filter_map(|w| w.parse().ok()).collect())
            .unwrap_or_default();
        let [lx, ly, lz] = size[..] else {
            return Err(import_err(
                &conf,
                "no `Packing size: LX LY LZ` line with three numbers",
            ));
        };
        match keyed(&text, "Boundaries mode:").map(str::trim) {
            Some("1") | None => Some(Container::Periodic { size: [lx, ly, lz] }),
            Some("3") => Some(Container::Box { size: [lx, ly, lz] }),
            Some(m) => {
                notes.push(format!(
                    "generation.conf boundaries mode {m} has no demcon container; it must be given"
                ));
                None
            }
        }
    } else {
        notes.push("no generation.conf: the container must be given".into());
        None
    };
    Ok(ImportedPacking {
        particles,
        container,
        notes,
    })
}

/// Reads the last snapshot of a LIGGGHTS/LAMMPS `dump custom` text file. Needs the columns
/// `x y z` (or `xu yu zu`, or scaled `xs ys zs`) and `radius` (or `diameter`), in any
/// order; sorts by `id` when present. The container comes from `ITEM: BOX BOUNDS`: periodic
/// when all three axes are `pp`, else a box; coordinates are shifted so the box starts at 0
/// and, in a periodic box, centres outside it are wrapped in.
pub fn read_liggghts_dump(path: &Path) -> Result<ImportedPacking, PackingError> {
    let text = read_text(path, "the LIGGGHTS/LAMMPS dump file")?;
    let lines: Vec<&str> = text.lines().collect();
    let start = lines
        .iter()
        .rposition(|l| l.trim().starts_with("ITEM: TIMESTEP"))
        .ok_or_else(|| import_err(path, "no `ITEM: TIMESTEP` line: not a LIGGGHTS/LAMMPS dump"))?;
    let perr = |k: usize, message: String| PackingError::Parse {
        path: path.to_path_buf(),
        line: k + 1,
        message,
    };
    let snapshot = &lines[start..];
    let find = |item: &str| {
        snapshot
            .iter()
            .position(|l| l.trim().starts_with(item))
            .map(|k| start + k)
    };
    let missing = |item: &str| import_err(path, format!("the last snapshot has no `{item}` section"));
    let timestep = lines.get(start + 1).map_or("", |l| l.trim()).to_string();
    let k_n = find("ITEM: NUMBER OF ATOMS").ok_or_else(|| missing("ITEM: NUMBER OF ATOMS"))?;
    let n: usize = lines
        .get(k_n + 1)
        .and_then(|l| l.trim().parse().ok())
        .ok_or_else(|| perr(k_n + 1, "expected the number of atoms".into()))?;
    let k_b = find("ITEM: BOX BOUNDS").ok_or_else(|| missing("ITEM: BOX BOUNDS"))?;
    let dbox = dump_box(path, &lines, k_b)?;
    let k_a = find("ITEM: ATOMS").ok_or_else(|| missing("ITEM: ATOMS"))?;
    let cols: Vec<&str> = lines[k_a].trim()["ITEM: ATOMS".len()..]
        .split_whitespace()
        .collect();
    let columns = dump_columns(path, &cols)?;
    let DumpBox {
        ref flags,
        lo,
        size,
        periodic,
    } = dbox;
    let mut rows: Vec<(i64, Vec3, f64)> = Vec::with_capacity(n);
    let mut wrapped = 0usize;
    for i in 0..n {
        let k = k_a + 1 + i;
        let Some(l) = lines.get(k) else {
            return Err(import_err(
                path,
                format!(
                    "the last snapshot (timestep {timestep}) stops after {i} of its {n} atoms: truncated?"
                ),
            ));
        };
        let (row, w) = columns.atom(path, k, i, l, &cols, &dbox)?;
        wrapped += w;
        rows.push(row);
    }
    rows.sort_by_key(|row| row.0);
    let particles = particle_set(
        path,
        rows.iter().map(|row| row.1).collect(),
        rows.iter().map(|row| row.2).collect(),
    )?;
    let mut notes = vec![format!(
        "last snapshot, timestep {timestep}, box bounds {}",
        flags.join(" ")
    )];
    if lo != [0.0; 3] {
        notes.push(format!(
            "coordinates shifted by ({}, {}, {}) so the box starts at 0",
            short(-lo[0]),
            short(-lo[1]),
            short(-lo[2])
        ));
    }
    if wrapped > 0 {
        notes.push(format!(
            "{wrapped} coordinates outside the periodic box wrapped into it"
        ));
    }
    let container = if periodic {
        Container::Periodic { size }
    } else {
        if flags.contains(&"pp") {
            notes.push(format!(
                "box bounds {}: partly periodic, imported as a box with walls on every face",
                flags.join(" ")
            ));
        }
        Container::Box { size }
    };
    Ok(ImportedPacking {
        particles,
        container: Some(container),
        notes,
    })
}

/// A dump's box: its boundary flags (`pp`, `ff`, …), its lower corner and size (m).
struct DumpBox<'t> {
    flags: Vec<&'t str>,
    lo: [f64; 3],
    size: [f64; 3],
    /// All three axes `pp`.
    periodic: bool,
}

/// The box of a dump's `ITEM: BOX BOUNDS` section at line `k_b` (orthogonal boxes only).
fn dump_box<'t>(path: &Path, lines: &[&'t str], k_b: usize) -> Result<DumpBox<'t>, PackingError> {
    let perr = |k: usize, message: String| PackingError::Parse {
        path: path.to_path_buf(),
        line: k + 1,
        message,
    };
    let flags: Vec<&str> = lines[k_b].trim()["ITEM: BOX BOUNDS".len()..]
        .split_whitespace()
        .collect();
    if flags.iter().any(|f| ["xy", "xz", "yz"].contains(f)) {
        return Err(perr(
            k_b,
            "a triclinic box (xy xz yz): only orthogonal boxes can be imported".into(),
        ));
    }
    if flags.len() != 3 {
        return Err(perr(
            k_b,
            format!(
                "expected three boundary flags (pp, ff, fs, …), found {}",
                flags.len()
            ),
        ));
    }
    let mut lo = [0.0; 3];
    let mut hi = [0.0; 3];
    for a in 0..3 {
        let k = k_b + 1 + a;
        let v: Vec<f64> = lines
            .get(k)
            .map(|l| l.split_whitespace().filter_map(|w| w.parse().ok()).collect())
            .unwrap_or_default();
        if v.len() != 2 || !v.iter().all(|x| x.is_finite()) || v[1] <= v[0] {
            return Err(perr(k, "expected the box bounds `lo hi` with lo < hi".into()));
        }
        (lo[a], hi[a]) = (v[0], v[1]);
    }
    Ok(DumpBox {
        periodic: flags.iter().all(|f| *f == "pp"),
        flags,
        lo,
        size: std::array::from_fn(|a| hi[a] - lo[a]),
    })
}

/// Where a dump's ATOMS columns hold the coordinates, the radius and the id.
#[derive(Debug, Clone, Copy)]
struct DumpColumns {
    /// Column of x, y, z (`x`, `xu` or scaled `xs`).
    xyz: [usize; 3],
    /// Whether some coordinate is scaled (`xs`, fractions of the box).
    scaled: bool,
    /// Column of the radius, and the factor to a radius (1, or 0.5 for a diameter).
    rcol: usize,
    rscale: f64,
    /// Column of the id, when there is one.
    idcol: Option<usize>,
}

/// The coordinate, radius and id columns among the ATOMS columns `cols`.
fn dump_columns(path: &Path, cols: &[&str]) -> Result<DumpColumns, PackingError> {
    let col = |names: &[&str]| names.iter().find_map(|n| cols.iter().position(|c| c == n));
    let mut xyz = [0usize; 3];
    let mut scaled = false;
    for (a, axis) in ["x", "y", "z"].iter().enumerate() {
        if let Some(c) = col(&[axis, &format!("{axis}u")]) {
            xyz[a] = c;
        } else if let Some(c) = col(&[&format!("{axis}s")]) {
            xyz[a] = c;
            scaled = true;
        } else {
            return Err(import_err(
                path,
                format!("the ATOMS columns ({}) have no `{axis}` column", cols.join(" ")),
            ));
        }
    }
    let (rcol, rscale) = match (col(&["radius"]), col(&["diameter"])) {
        (Some(c), _) => (c, 1.0),
        (None, Some(c)) => (c, 0.5),
        (None, None) => {
            return Err(import_err(
                path,
                format!(
                    "the ATOMS columns ({}) have no `radius` column: add radius to the dump custom command",
                    cols.join(" ")
                ),
            ));
        }
    };
    let idcol = col(&["id"]);
    Ok(DumpColumns {
        xyz,
        scaled,
        rcol,
        rscale,
        idcol,
    })
}

impl DumpColumns {
    /// Atom `i` of the snapshot, at line `k` (`line`, of the ATOMS columns `cols`): its id
    /// (or `i`), centre shifted into the box (m) and radius (m), and how many of its
    /// coordinates were wrapped into a periodic box.
    fn atom(
        &self,
        path: &Path,
        k: usize,
        i: usize,
        line: &str,
        cols: &[&str],
        dbox: &DumpBox<'_>,
    ) -> Result<((i64, Vec3, f64), usize), PackingError> {
        let perr = |k: usize, message: String| PackingError::Parse {
            path: path.to_path_buf(),
            line: k + 1,
            message,
        };
        let DumpColumns {
            xyz,
            scaled,
            rcol,
            rscale,
            idcol,
        } = *self;
        let (lo, size, periodic) = (dbox.lo, dbox.size, dbox.periodic);
        let l = line;
        let mut wrapped = 0;
        let w: Vec<&str> = l.split_whitespace().collect();
        if w.len() != cols.len() {
            return Err(perr(
                k,
                format!(
                    "expected {} columns ({}), found {}",
                    cols.len(),
                    cols.join(" "),
                    w.len()
                ),
            ));
        }
        let num = |c: usize| {
            w[c].parse::<f64>()
                .ok()
                .filter(|x| x.is_finite())
                .ok_or_else(|| perr(k, format!("`{}` ({}) is not a finite number", w[c], cols[c])))
        };
        let mut p = [0.0; 3];
        for a in 0..3 {
            let v = num(xyz[a])?;
            p[a] = if scaled && cols[xyz[a]].ends_with('s') {
                v * size[a]
            } else {
                v - lo[a]
            };
            if periodic && !(0.0..size[a]).contains(&p[a]) {
                p[a] = p[a].rem_euclid(size[a]);
                wrapped += 1;
            }
        }
        let r = num(rcol)? * rscale;
        if r <= 0.0 {
            return Err(perr(k, format!("radius {} must be > 0", short(r))));
        }
        let id = match idcol {
            Some(c) => w[c]
                .parse::<i64>()
                .map_err(|_| perr(k, format!("`{}` (id) is not an integer", w[c])))?,
            None => i as i64,
        };
        Ok(((id, Vec3::new(p[0], p[1], p[2]), r), wrapped))
    }
}

/// Reads YADE's `export.text`: a `#format x_y_z_r…` header (extra columns after `r` are
/// ignored), other `#` lines are comments, then `x y z r` per line. YADE gives no container.
pub fn read_yade_text(path: &Path) -> Result<ImportedPacking, PackingError> {
    let text = read_text(path, "the YADE export.text file")?;
    let mut centres = vec![];
    let mut radii = vec![];
    let mut format = None;
    for (k, raw) in text.lines().enumerate() {
        let perr = |message: String| PackingError::Parse {
            path: path.to_path_buf(),
            line: k + 1,
            message,
        };
        let l = raw.trim();
        if l.is_empty() {
            continue;
        }
        if let Some(h) = l.strip_prefix('#') {
            if let Some(f) = h.trim().strip_prefix("format") {
                let f = f.trim();
                if !f.starts_with("x_y_z_r") {
                    return Err(perr(format!(
                        "`#format {f}`: only formats starting with x_y_z_r can be imported"
                    )));
                }
                format = Some(f.to_string());
            }
            continue;
        }
        let w: Vec<&str> = l.split_whitespace().collect();
        if w.len() < 4 {
            return Err(perr(format!(
                "expected at least 4 numbers `x y z r`, found {} fields",
                w.len()
            )));
        }
        let mut v = [0.0; 4];
        for q in 0..4 {
            v[q] = w[q]
                .parse::<f64>()
                .ok()
                .filter(|x| x.is_finite())
                .ok_or_else(|| perr(format!("`{}` is not a finite number", w[q])))?;
        }
        if v[3] <= 0.0 {
            return Err(perr(format!("radius {} must be > 0", short(v[3]))));
        }
        centres.push(Vec3::new(v[0], v[1], v[2]));
        radii.push(v[3]);
    }
    let particles = particle_set(path, centres, radii)?;
    let notes = vec![match format {
        Some(f) => format!("YADE #format {f}"),
        None => "no #format line: read as x y z r".into(),
    }];
    Ok(ImportedPacking {
        particles,
        container: None,
        notes,
    })
}
