//! Checkpoint files of a transient run, from which `demcon run --resume` continues a killed
//! run bit for bit.
//!
//! Where: `OUT.checkpoint`, a file beside the output folder `OUT` ([`checkpoint_path`]). The
//! folder itself is written whole at the end of a run (a temporary sibling renamed in place),
//! so a killed run never leaves one; the checkpoint lies outside it, survives the kill, and is
//! removed once the run's outputs are written ([`remove_checkpoint`]). Each checkpoint
//! replaces the last through a temporary file (`OUT.checkpoint.tmp`), synced, then renamed: a
//! kill at any moment leaves the previous checkpoint or the new one, whole.
//!
//! Format (version 1), little-endian throughout:
//!
//! ```text
//! magic "DEMCONCP" (8 bytes), format version u32
//! demcon version: str                          (str = u64 byte count, UTF-8 bytes)
//! scene sections: u64 count, each (name: str, FNV-1a 64 of its canonical JSON: u64), a section
//!                being a top-level field of the scene or a field of a struct one (thermal.solver)
//! packing: u64 particle count, u64 hash of centres, radii, phases and container
//! transient: scheme str, dt f64, t_end f64, segment u64, segment_steps u64, steps u64, t f64,
//!            temperatures, initial_temperatures, sources: vec (u64 count, f64 each),
//!            energy_sources_j, energy_boundary_j, turnover_boundary_j, turnover_sources_j f64,
//!            solver_iterations u64, max_relative_residual f64, envelope 3 × f64, wall_s f64
//! snapshots: u64 count, each (t f64, vec)
//! coupling: u8 0 | 1, then (last_temperatures vec, solves u64, solves_wall_s f64)
//! checksum: FNV-1a 64 of every byte before it, u64
//! ```
//!
//! Every f64 is stored as its exact bits. Reading checks the magic, the version, the checksum
//! and every length against the bytes left, so a truncated or damaged file is an error that
//! says so, never a panic or a huge allocation. [`Fingerprint::check_scene`] and
//! [`Fingerprint::check_packing`] refuse a checkpoint written for another scene (naming the
//! sections that differ; `thermal.checkpoint` itself may change) or another packing.

use std::io::Write;
use std::path::{Path, PathBuf};

use demcon_model::{CouplingState, Model, RunCheckpoint};
use demcon_thermal::TransientState;

use crate::config::SceneConfig;
use crate::error::SceneError;

/// The first bytes of a checkpoint file.
pub const MAGIC: &[u8; 8] = b"DEMCONCP";
/// The format version this build writes and reads.
pub const FORMAT_VERSION: u32 = 1;

/// The checkpoint file of the output folder `out`: `OUT.checkpoint` beside it.
///
/// # Errors
/// `out` names no folder (`.`, `..`, a root).
pub fn checkpoint_path(out: &Path) -> Result<PathBuf, SceneError> {
    let (parent, name) = crate::output::split_dir(out)?;
    let mut file = name.to_os_string();
    file.push(".checkpoint");
    Ok(parent.join(file))
}

/// Removes the checkpoint at `path`, and the temporary file a kill during a write may have
/// left beside it (nothing to do when there is none).
///
/// # Errors
/// A file exists and cannot be removed.
pub fn remove_checkpoint(path: &Path) -> Result<(), SceneError> {
    for p in [path.to_path_buf(), tmp_path(path)] {
        match std::fs::remove_file(&p) {
            Err(e) if e.kind() != std::io::ErrorKind::NotFound => {
                return Err(SceneError::Io { path: p, source: e });
            }
            _ => {}
        }
    }
    Ok(())
}

/// The temporary file a checkpoint is written to before the rename: `path.tmp`.
fn tmp_path(path: &Path) -> PathBuf {
    let mut tmp = path.as_os_str().to_os_string();
    tmp.push(".tmp");
    PathBuf::from(tmp)
}

/// What a checkpoint was written for: the demcon version, the scene (a hash per top-level
/// section) and the packing.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Fingerprint {
    /// The demcon version that wrote it.
    pub version: String,
    /// (section, FNV-1a 64 of its canonical JSON) per section of the scene, in order: each
    /// top-level field, or each of its fields when it is a struct (`thermal.solver`,
    /// `outputs.times`); `thermal.checkpoint` is left out (the schedule never changes
    /// results).
    pub sections: Vec<(String, u64)>,
    /// Particles of the built model.
    pub n_particles: u64,
    /// FNV-1a 64 of the built model's centres, radii, phases (exact bits), container and cut
    /// contacts.
    pub packing: u64,
}

impl Fingerprint {
    /// The fingerprint of a scene before its model is built (`packing` left at 0).
    pub fn of_scene(cfg: &SceneConfig) -> Self {
        let mut cfg = cfg.clone();
        if let Some(t) = cfg.thermal.as_mut() {
            t.checkpoint = None;
        }
        let value = serde_json::to_value(&cfg).expect("a scene serialises");
        let hash = |v: &serde_json::Value| fnv1a(v.to_string().as_bytes());
        // A section that is a struct (lower-case keys; enum variants are upper-case) is
        // hashed field by field, so a refusal can name the field.
        let is_struct = |v: &serde_json::Value| {
            v.as_object()
                .is_some_and(|m| !m.is_empty() && m.keys().all(|k| k.starts_with(|c: char| c.is_lowercase())))
        };
        let mut sections = Vec::new();
        match &value {
            serde_json::Value::Object(map) => {
                for (k, v) in map {
                    match v.as_object() {
                        Some(fields) if is_struct(v) => {
                            sections.extend(fields.iter().map(|(f, x)| (format!("{k}.{f}"), hash(x))));
                        }
                        _ => sections.push((k.clone(), hash(v))),
                    }
                }
            }
            other => sections.push((String::new(), hash(other))),
        }
        Self {
            version: env!("CARGO_PKG_VERSION").into(),
            sections,
            n_particles: 0,
            packing: 0,
        }
    }

    /// Adds the packing of the built model.
    pub fn with_packing(mut self, model: &Model) -> Self {
        let p = &model.particles;
        let mut h = Fnv::new();
        h.write(&(p.len() as u64).to_le_bytes());
        for (c, r) in p.centres.iter().zip(&p.radii) {
            for k in 0..3 {
                h.write(&c[k].to_bits().to_le_bytes());
            }
            h.write(&r.to_bits().to_le_bytes());
        }
        for ph in &p.phases {
            h.write(&ph.to_le_bytes());
        }
        h.write(format!("{:?}", model.container).as_bytes());
        // The contacts cut by cracks and broken bonds (a changed `cut_contacts` file changes
        // them while the scene's text does not); nothing is added for a model without any, so
        // the fingerprints of such models are unchanged.
        for c in model.cut_contacts() {
            h.write(&c.pair[0].to_le_bytes());
            h.write(&c.pair[1].to_le_bytes());
        }
        self.n_particles = p.len() as u64;
        self.packing = h.finish();
        self
    }

    /// Refuses a checkpoint (`self`, read from `path`) written by another demcon version or
    /// for another scene than `current`, naming the sections that differ.
    ///
    /// # Errors
    /// [`SceneError::Checkpoint`] saying what differs.
    pub fn check_scene(&self, current: &Fingerprint, path: &Path) -> Result<(), SceneError> {
        if self.version != current.version {
            return Err(refused(
                path,
                format!(
                    "was written by demcon {}, this is demcon {}: finish the run with that version, or remove \
                     the checkpoint to start over",
                    self.version, current.version
                ),
            ));
        }
        let mut differ: Vec<&str> = current
            .sections
            .iter()
            .filter(|(k, h)| !self.sections.iter().any(|(k2, h2)| k2 == k && h2 == h))
            .map(|(k, _)| k.as_str())
            .collect();
        differ.extend(
            self.sections
                .iter()
                .filter(|(k, _)| !current.sections.iter().any(|(k2, _)| k2 == k))
                .map(|(k, _)| k.as_str()),
        );
        if !differ.is_empty() {
            return Err(refused(
                path,
                format!(
                    "was written for another scene: {} differ{} from the scene's (only thermal.checkpoint may \
                     change between a run and its resumption): restore the scene, or remove the checkpoint to \
                     start over",
                    differ.join(", "),
                    if differ.len() == 1 { "s" } else { "" }
                ),
            ));
        }
        Ok(())
    }

    /// Refuses a checkpoint (`self`) written on another packing than the one just built
    /// (`current`).
    ///
    /// # Errors
    /// [`SceneError::Checkpoint`] with the particle counts and hashes.
    pub fn check_packing(&self, current: &Fingerprint, path: &Path) -> Result<(), SceneError> {
        if (self.n_particles, self.packing) != (current.n_particles, current.packing) {
            return Err(refused(
                path,
                format!(
                    "was written on another packing ({} particles, hash {:016x}) than the one built now ({} \
                     particles, hash {:016x}): was the packing file changed? Restore it, or remove the \
                     checkpoint to start over",
                    self.n_particles, self.packing, current.n_particles, current.packing
                ),
            ));
        }
        Ok(())
    }
}

fn refused(path: &Path, problem: String) -> SceneError {
    SceneError::Checkpoint {
        path: path.into(),
        problem,
    }
}

/// The bytes of a checkpoint file.
pub fn encode(fingerprint: &Fingerprint, ck: &RunCheckpoint) -> Vec<u8> {
    let s = &ck.transient;
    let mut w = Writer(Vec::with_capacity(
        256 + 8 * (4 * s.temperatures.len() + ck.snapshots.iter().map(|x| x.1.len() + 1).sum::<usize>()),
    ));
    w.0.extend_from_slice(MAGIC);
    w.0.extend_from_slice(&FORMAT_VERSION.to_le_bytes());
    w.str(&fingerprint.version);
    w.u64(fingerprint.sections.len() as u64);
    for (name, h) in &fingerprint.sections {
        w.str(name);
        w.u64(*h);
    }
    w.u64(fingerprint.n_particles);
    w.u64(fingerprint.packing);
    w.str(&s.scheme);
    w.f64(s.dt);
    w.f64(s.t_end);
    w.u64(s.segment);
    w.u64(s.segment_steps);
    w.u64(s.steps);
    w.f64(s.t);
    w.vec(&s.temperatures);
    w.vec(&s.initial_temperatures);
    w.vec(&s.sources);
    for v in [
        s.energy_sources_j,
        s.energy_boundary_j,
        s.turnover_boundary_j,
        s.turnover_sources_j,
    ] {
        w.f64(v);
    }
    w.u64(s.solver_iterations);
    w.f64(s.max_relative_residual);
    for v in s.envelope {
        w.f64(v);
    }
    w.f64(s.wall_s);
    w.u64(ck.snapshots.len() as u64);
    for (t, v) in &ck.snapshots {
        w.f64(*t);
        w.vec(v);
    }
    match &ck.coupling {
        None => w.0.push(0),
        Some(c) => {
            w.0.push(1);
            w.vec(&c.last_temperatures);
            w.u64(c.solves);
            w.f64(c.solves_wall_s);
        }
    }
    let sum = fnv1a(&w.0);
    w.u64(sum);
    w.0
}

/// Reads the bytes of a checkpoint file (`path` only names it in errors).
///
/// # Errors
/// [`SceneError::Checkpoint`]: not a checkpoint, another format version, truncated or
/// damaged (checksum, a length beyond the bytes left, bytes after the end, a bad value).
pub fn decode(bytes: &[u8], path: &Path) -> Result<(Fingerprint, RunCheckpoint), SceneError> {
    let damaged = |what: String| {
        refused(
            path,
            format!("is damaged ({what}): remove it and start the run over"),
        )
    };
    if bytes.len() < MAGIC.len() && MAGIC.starts_with(bytes) {
        return Err(damaged(format!("truncated: {} bytes", bytes.len())));
    }
    if bytes.len() < MAGIC.len() || &bytes[..MAGIC.len()] != MAGIC {
        return Err(refused(
            path,
            "is not a demcon checkpoint (wrong first bytes)".into(),
        ));
    }
    if bytes.len() < MAGIC.len() + 4 + 8 {
        return Err(damaged(format!("truncated: {} bytes", bytes.len())));
    }
    let version = u32::from_le_bytes(bytes[8..12].try_into().expect("4 bytes"));
    if version != FORMAT_VERSION {
        return Err(refused(
            path,
            format!(
                "has format version {version}; this demcon reads version {FORMAT_VERSION}: finish the run with \
                 the demcon that wrote it, or remove the checkpoint to start over"
            ),
        ));
    }
    let (body, sum) = bytes.split_at(bytes.len() - 8);
    if fnv1a(body) != u64::from_le_bytes(sum.try_into().expect("8 bytes")) {
        return Err(damaged(
            "truncated or corrupt: its checksum does not match".into(),
        ));
    }
    let mut r = Reader { bytes: body, pos: 12 };
    read_body(&mut r).map_err(damaged)
}

fn read_body(r: &mut Reader<'_>) -> Result<(Fingerprint, RunCheckpoint), String> {
    let version = r.str()?;
    let n_sections = r.count(16)?;
    let mut sections = Vec::with_capacity(n_sections);
    for _ in 0..n_sections {
        let name = r.str()?;
        sections.push((name, r.u64()?));
    }
    let fingerprint = Fingerprint {
        version,
        sections,
        n_particles: r.u64()?,
        packing: r.u64()?,
    };
    let scheme = r.str()?;
    let (dt, t_end) = (r.f64()?, r.f64()?);
    let (segment, segment_steps, steps) = (r.u64()?, r.u64()?, r.u64()?);
    let t = r.f64()?;
    let (temperatures, initial_temperatures, sources) = (r.vec()?, r.vec()?, r.vec()?);
    let mut ledger = [0.0; 4];
    for v in &mut ledger {
        *v = r.f64()?;
    }
    let solver_iterations = r.u64()?;
    let max_relative_residual = r.f64()?;
    let envelope = [r.f64()?, r.f64()?, r.f64()?];
    let wall_s = r.f64()?;
    let n_snapshots = r.count(16)?;
    let mut snapshots = Vec::with_capacity(n_snapshots);
    for _ in 0..n_snapshots {
        let t = r.f64()?;
        snapshots.push((t, r.vec()?));
    }
    let coupling = match r.take(1)?[0] {
        0 => None,
        1 => Some(CouplingState {
            last_temperatures: r.vec()?,
            solves: r.u64()?,
            solves_wall_s: r.f64()?,
        }),
        b => return Err(format!("coupling flag {b} at byte {}", r.pos - 1)),
    };
    if r.pos != r.bytes.len() {
        return Err(format!("{} bytes after the end", r.bytes.len() - r.pos));
    }
    let [
        energy_sources_j,
        energy_boundary_j,
        turnover_boundary_j,
        turnover_sources_j,
    ] = ledger;
    let transient = TransientState {
        scheme,
        dt,
        t_end,
        segment,
        segment_steps,
        steps,
        t,
        temperatures,
        initial_temperatures,
        sources,
        energy_sources_j,
        energy_boundary_j,
        turnover_boundary_j,
        turnover_sources_j,
        solver_iterations,
        max_relative_residual,
        envelope,
        wall_s,
    };
    Ok((
        fingerprint,
        RunCheckpoint {
            transient,
            snapshots,
            coupling,
        },
    ))
}

/// Writes a checkpoint to `path` through `path.tmp`, synced, then renamed over it.
///
/// # Errors
/// [`SceneError::Io`] naming the file that could not be written.
pub fn write_checkpoint(
    path: &Path,
    fingerprint: &Fingerprint,
    ck: &RunCheckpoint,
) -> Result<(), SceneError> {
    let tmp = tmp_path(path);
    let io = |p: &Path| {
        let p = p.to_path_buf();
        move |source| SceneError::Io { path: p, source }
    };
    let mut f = std::fs::File::create(&tmp).map_err(io(&tmp))?;
    f.write_all(&encode(fingerprint, ck)).map_err(io(&tmp))?;
    f.sync_all().map_err(io(&tmp))?;
    drop(f);
    std::fs::rename(&tmp, path).map_err(io(path))?;
    Ok(())
}

/// Reads the checkpoint at `path`.
///
/// # Errors
/// [`SceneError::Checkpoint`] when there is none or it cannot be read (see [`decode`]).
pub fn read_checkpoint(path: &Path) -> Result<(Fingerprint, RunCheckpoint), SceneError> {
    let bytes = match std::fs::read(path) {
        Ok(b) => b,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
            return Err(refused(
                path,
                "does not exist: there is no interrupted run to resume (a run writes a checkpoint only when its \
                 scene sets thermal.checkpoint, and removes it once its outputs are written)"
                    .into(),
            ));
        }
        Err(source) => {
            return Err(SceneError::Io {
                path: path.into(),
                source,
            });
        }
    };
    decode(&bytes, path)
}

/// FNV-1a 64 of `bytes`: a stable hash (the same in every build) for fingerprints and the
/// checksum.
pub fn fnv1a(bytes: &[u8]) -> u64 {
    let mut h = Fnv::new();
    h.write(bytes);
    h.finish()
}

/// FNV-1a 64, fed in pieces.
struct Fnv(u64);

impl Fnv {
    fn new() -> Self {
        Self(0xcbf2_9ce4_8422_2325)
    }

    fn write(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.0 ^= u64::from(b);
            self.0 = self.0.wrapping_mul(0x0000_0100_0000_01b3);
        }
    }

    fn finish(&self) -> u64 {
        self.0
    }
}

struct Writer(Vec<u8>);

impl Writer {
    fn u64(&mut self, v: u64) {
        self.0.extend_from_slice(&v.to_le_bytes());
    }

    fn f64(&mut self, v: f64) {
        self.u64(v.to_bits());
    }

    fn str(&mut self, s: &str) {
        self.u64(s.len() as u64);
        self.0.extend_from_slice(s.as_bytes());
    }

    fn vec(&mut self, v: &[f64]) {
        self.u64(v.len() as u64);
        for x in v {
            self.f64(*x);
        }
    }
}

/// Reads the body of a checkpoint; every length is checked against the bytes left.
struct Reader<'a> {
    bytes: &'a [u8],
    pos: usize,
}

impl<'a> Reader<'a> {
    fn take(&mut self, n: usize) -> Result<&'a [u8], String> {
        let left = self.bytes.len() - self.pos;
        if n > left {
            return Err(format!(
                "truncated: {n} bytes needed at byte {}, {left} left",
                self.pos
            ));
        }
        let out = &self.bytes[self.pos..self.pos + n];
        self.pos += n;
        Ok(out)
    }

    fn u64(&mut self) -> Result<u64, String> {
        Ok(u64::from_le_bytes(self.take(8)?.try_into().expect("8 bytes")))
    }

    fn f64(&mut self) -> Result<f64, String> {
        Ok(f64::from_bits(self.u64()?))
    }

    /// A count of items of at least `min_bytes` each, checked against the bytes left.
    fn count(&mut self, min_bytes: usize) -> Result<usize, String> {
        let at = self.pos;
        let n = self.u64()?;
        let left = (self.bytes.len() - self.pos) as u64;
        if n > left / min_bytes as u64 {
            return Err(format!(
                "a count of {n} at byte {at} needs more than the {left} bytes left"
            ));
        }
        Ok(n as usize)
    }

    fn str(&mut self) -> Result<String, String> {
        let n = self.count(1)?;
        let at = self.pos;
        String::from_utf8(self.take(n)?.to_vec()).map_err(|_| format!("text at byte {at} is not UTF-8"))
    }

    fn vec(&mut self) -> Result<Vec<f64>, String> {
        let n = self.count(8)?;
        let raw = self.take(8 * n)?;
        Ok(raw
            .chunks_exact(8)
            .map(|c| f64::from_bits(u64::from_le_bytes(c.try_into().expect("8 bytes"))))
            .collect())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample() -> (Fingerprint, RunCheckpoint) {
        let fp = Fingerprint {
            version: "0.1.0".into(),
            sections: vec![("name".into(), 1), ("thermal".into(), 2)],
            n_particles: 3,
            packing: 0xdead_beef,
        };
        let transient = TransientState {
            scheme: "crank-nicolson".into(),
            dt: 0.1,
            t_end: 1.0,
            segment: 2,
            segment_steps: 3,
            steps: 7,
            t: 0.7000000000000001,
            temperatures: vec![1.0, -0.0, f64::MIN_POSITIVE, 4.5],
            initial_temperatures: vec![0.0; 4],
            sources: vec![1e-300, 2.0, 0.0, -3.0],
            energy_sources_j: 1.5,
            energy_boundary_j: -2.25,
            turnover_boundary_j: 3.0,
            turnover_sources_j: 4.0,
            solver_iterations: 42,
            max_relative_residual: 1e-11,
            envelope: [0.0, 0.0, 0.0],
            wall_s: 0.5,
        };
        let ck = RunCheckpoint {
            transient,
            snapshots: vec![(0.0, vec![1.0, 2.0, 3.0]), (0.5, vec![4.0, 5.0, 6.0])],
            coupling: Some(CouplingState {
                last_temperatures: vec![1.0, 2.0, 3.0],
                solves: 5,
                solves_wall_s: 0.01,
            }),
        };
        (fp, ck)
    }

    #[test]
    fn a_checkpoint_reads_back_bit_for_bit() {
        let (fp, ck) = sample();
        let bytes = encode(&fp, &ck);
        let (fp2, ck2) = decode(&bytes, Path::new("x")).unwrap();
        assert_eq!(fp, fp2);
        assert_eq!(ck, ck2);
        // -0.0 == 0.0 for PartialEq: compare bits.
        assert_eq!(ck2.transient.temperatures[1].to_bits(), (-0.0f64).to_bits());
        let mut plain = ck.clone();
        plain.coupling = None;
        let (_, back) = decode(&encode(&fp, &plain), Path::new("x")).unwrap();
        assert_eq!(back, plain);
    }

    #[test]
    fn every_truncation_and_every_flipped_byte_is_an_error_not_a_panic() {
        let (fp, ck) = sample();
        let bytes = encode(&fp, &ck);
        for n in 0..bytes.len() {
            let e = decode(&bytes[..n], Path::new("x")).unwrap_err().to_string();
            assert!(
                e.contains("damaged") || e.contains("not a demcon checkpoint"),
                "{n}: {e}"
            );
        }
        for i in 0..bytes.len() {
            let mut b = bytes.clone();
            b[i] ^= 0x10;
            assert!(decode(&b, Path::new("x")).is_err(), "byte {i}");
        }
    }

    #[test]
    fn lengths_beyond_the_file_are_refused_before_any_allocation() {
        // A body whose first vector claims 2⁶⁰ values, with a valid checksum.
        let (fp, ck) = sample();
        let bytes = encode(&fp, &ck);
        let mut r = Reader {
            bytes: &bytes[..bytes.len() - 8],
            pos: 12,
        };
        r.str().unwrap();
        let mut body = bytes[..r.pos].to_vec();
        body.extend_from_slice(&(1u64 << 60).to_le_bytes());
        let sum = fnv1a(&body);
        body.extend_from_slice(&sum.to_le_bytes());
        let e = decode(&body, Path::new("x")).unwrap_err().to_string();
        assert!(e.contains("damaged") && e.contains("count"), "{e}");
        // Another format version and another file kind are named as such.
        let mut v2 = bytes.clone();
        v2[8] = 2;
        let e = decode(&v2, Path::new("x")).unwrap_err().to_string();
        assert!(e.contains("format version 2"), "{e}");
        let e = decode(b"x y z r\n", Path::new("x")).unwrap_err().to_string();
        assert!(e.contains("not a demcon checkpoint"), "{e}");
    }

    #[test]
    fn the_checkpoint_lies_beside_the_output_folder() {
        let p = checkpoint_path(Path::new("out/slab")).unwrap();
        assert_eq!(p, Path::new("out/slab.checkpoint"));
        let p = checkpoint_path(Path::new("out/slab/")).unwrap();
        assert_eq!(p, Path::new("out/slab.checkpoint"));
        assert_eq!(
            checkpoint_path(Path::new("slab")).unwrap(),
            Path::new("./slab.checkpoint")
        );
        assert!(checkpoint_path(Path::new("..")).is_err());
    }

    #[test]
    fn a_fingerprint_names_the_sections_that_differ() {
        let (fp, _) = sample();
        let mut other = fp.clone();
        other.sections[1].1 = 3;
        let e = fp.check_scene(&other, Path::new("c")).unwrap_err().to_string();
        assert!(e.contains("thermal differs") && !e.contains("name"), "{e}");
        let mut other = fp.clone();
        other.sections.push(("electric".into(), 4));
        let e = fp.check_scene(&other, Path::new("c")).unwrap_err().to_string();
        assert!(e.contains("electric"), "{e}");
        let mut other = fp.clone();
        other.version = "9.9.9".into();
        let e = fp.check_scene(&other, Path::new("c")).unwrap_err().to_string();
        assert!(e.contains("9.9.9"), "{e}");
        let mut other = fp.clone();
        other.packing = 1;
        assert!(fp.check_scene(&other, Path::new("c")).is_ok());
        let e = fp.check_packing(&other, Path::new("c")).unwrap_err().to_string();
        assert!(e.contains("another packing"), "{e}");
    }
}
