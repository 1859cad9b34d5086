//! VTK XML unstructured-grid output (`.vtu`) of particles as vertex cells, with the data in
//! one raw appended binary block (little-endian, UInt64 block headers): about 40× faster
//! than base64 and read by ParaView. Written atomically.

use std::io::Write;
use std::path::Path;

use demcon_core::{ParticleSet, Vec3};

use crate::atomic::write_atomic;
use crate::error::PostError;

/// Values of a per-particle field.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum FieldData<'a> {
    /// One number per particle, written as Float64.
    Scalars(&'a [f64]),
    /// One 3-vector per particle, written as Float64 × 3.
    Vectors(&'a [Vec3]),
    /// One integer per particle (flags, ids, counts), written as Int32.
    Ints(&'a [i32]),
}

/// A named per-particle field for [`write_vtu`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Field<'a> {
    /// Name shown in ParaView (unique; not `radius` or `phase`, which are always written).
    pub name: &'a str,
    /// The values, one per particle.
    pub data: FieldData<'a>,
}

impl<'a> Field<'a> {
    /// A scalar field (e.g. temperature, K).
    pub fn scalars(name: &'a str, data: &'a [f64]) -> Self {
        Self {
            name,
            data: FieldData::Scalars(data),
        }
    }
    /// A vector field (e.g. heat flux, W/m²).
    pub fn vectors(name: &'a str, data: &'a [Vec3]) -> Self {
        Self {
            name,
            data: FieldData::Vectors(data),
        }
    }
    /// An integer field (e.g. a truncation flag, 0/1).
    pub fn ints(name: &'a str, data: &'a [i32]) -> Self {
        Self {
            name,
            data: FieldData::Ints(data),
        }
    }
}

/// One appended data array.
#[derive(Clone, Copy)]
enum Block<'a> {
    F64(&'a [f64]),
    Vec3(&'a [Vec3]),
    I32(&'a [i32]),
    U16(&'a [u16]),
    /// `0, 1, …, n−1` (connectivity) or `1, 2, …, n` (offsets) as Int32 or Int64.
    Seq {
        first: u64,
        n: usize,
        wide: bool,
    },
    /// `n` copies of one byte (cell types).
    U8Const {
        value: u8,
        n: usize,
    },
}

impl Block<'_> {
    fn vtk_type(&self) -> &'static str {
        match self {
            Block::F64(_) | Block::Vec3(_) => "Float64",
            Block::I32(_) => "Int32",
            Block::U16(_) => "UInt16",
            Block::Seq { wide: false, .. } => "Int32",
            Block::Seq { wide: true, .. } => "Int64",
            Block::U8Const { .. } => "UInt8",
        }
    }
    fn components(&self) -> usize {
        if matches!(self, Block::Vec3(_)) { 3 } else { 1 }
    }
    fn bytes(&self) -> u64 {
        (match *self {
            Block::F64(v) => 8 * v.len(),
            Block::Vec3(v) => 24 * v.len(),
            Block::I32(v) => 4 * v.len(),
            Block::U16(v) => 2 * v.len(),
            Block::Seq { n, wide, .. } => n * if wide { 8 } else { 4 },
            Block::U8Const { n, .. } => n,
        }) as u64
    }

    /// Writes the UInt64 byte count, then the little-endian values.
    fn write(&self, w: &mut impl Write) -> std::io::Result<()> {
        w.write_all(&self.bytes().to_le_bytes())?;
        const CHUNK: usize = 4096;
        let mut buf: Vec<u8> = Vec::with_capacity(CHUNK * 24);
        macro_rules! chunked {
            ($data:expr, |$x:ident, $b:ident| $body:expr) => {
                for chunk in $data.chunks(CHUNK) {
                    buf.clear();
                    for $x in chunk {
                        let $b = &mut buf;
                        $body;
                    }
                    w.write_all(&buf)?;
                }
            };
        }
        match *self {
            Block::F64(v) => chunked!(v, |x, b| b.extend_from_slice(&x.to_le_bytes())),
            Block::Vec3(v) => chunked!(v, |x, b| {
                b.extend_from_slice(&x.x.to_le_bytes());
                b.extend_from_slice(&x.y.to_le_bytes());
                b.extend_from_slice(&x.z.to_le_bytes());
            }),
            Block::I32(v) => chunked!(v, |x, b| b.extend_from_slice(&x.to_le_bytes())),
            Block::U16(v) => chunked!(v, |x, b| b.extend_from_slice(&x.to_le_bytes())),
            Block::Seq { first, n, wide } => {
                let mut i = 0usize;
                while i < n {
                    let end = (i + CHUNK).min(n);
                    buf.clear();
                    for k in i..end {
                        let v = first + k as u64;
                        if wide {
                            buf.extend_from_slice(&(v as i64).to_le_bytes());
                        } else {
                            buf.extend_from_slice(&(v as i32).to_le_bytes());
                        }
                    }
                    w.write_all(&buf)?;
                    i = end;
                }
            }
            Block::U8Const { value, n } => {
                let row = [value; CHUNK];
                let mut left = n;
                while left > 0 {
                    let m = left.min(CHUNK);
                    w.write_all(&row[..m])?;
                    left -= m;
                }
            }
        }
        Ok(())
    }
}

/// Escapes a string for an XML attribute.
fn xml_escape(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    for c in s.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&apos;"),
            c => out.push(c),
        }
    }
    out
}

/// Checks a field: name, length, finite values.
fn check_field(f: &Field, n: usize, seen: &[&str]) -> Result<(), PostError> {
    let name = f.name;
    if name.is_empty() || name.chars().any(char::is_control) {
        return Err(PostError::invalid(
            "field name",
            format!("{name:?}"),
            "a non-empty name without control characters",
        ));
    }
    if ["radius", "phase"].contains(&name) || seen.contains(&name) {
        return Err(PostError::invalid(
            "field name",
            name,
            "a name used once and not `radius` or `phase` (always written)",
        ));
    }
    let len = match f.data {
        FieldData::Scalars(v) => v.len(),
        FieldData::Vectors(v) => v.len(),
        FieldData::Ints(v) => v.len(),
    };
    if len != n {
        return Err(PostError::invalid(
            format!("field {name}"),
            format!("{len} values"),
            format!("one per particle ({n})"),
        ));
    }
    let bad = match f.data {
        FieldData::Scalars(v) => v.iter().position(|x| !x.is_finite()),
        FieldData::Vectors(v) => v.iter().position(|x| !x.iter().all(|c| c.is_finite())),
        FieldData::Ints(_) => None,
    };
    if let Some(i) = bad {
        return Err(PostError::invalid(
            format!("field {name}[{i}]"),
            "a non-finite value",
            "finite values (flag missing data with an Ints field instead)",
        ));
    }
    Ok(())
}

/// Writes the particles as a VTK XML unstructured grid of vertex cells: points at the centres
/// (m), point data `radius` (m, Float64) and `phase` (UInt16) always, then `fields` in order.
/// Returns the number of bytes written. In ParaView, a "Glyph" filter with sphere glyphs
/// scaled by `radius` (scale factor 2, since a glyph of scale 1 has diameter 1) shows the
/// spheres.
///
/// Errors: a field of the wrong length, with non-finite values or a bad or repeated name,
/// or a file-system failure. The file is written atomically (temporary file + rename).
pub fn write_vtu(
    path: impl AsRef<Path>,
    particles: &ParticleSet,
    fields: &[Field],
) -> Result<u64, PostError> {
    crate::error::check_particles(particles)?;
    let n = particles.len();
    let mut seen: Vec<&str> = Vec::new();
    for f in fields {
        check_field(f, n, &seen)?;
        seen.push(f.name);
    }
    let wide = n >= i32::MAX as usize;
    let mut point_data: Vec<(String, Block)> = vec![
        ("radius".into(), Block::F64(&particles.radii)),
        ("phase".into(), Block::U16(&particles.phases)),
    ];
    for f in fields {
        let b = match f.data {
            FieldData::Scalars(v) => Block::F64(v),
            FieldData::Vectors(v) => Block::Vec3(v),
            FieldData::Ints(v) => Block::I32(v),
        };
        point_data.push((xml_escape(f.name), b));
    }
    let points = Block::Vec3(&particles.centres);
    let cells = [
        ("connectivity", Block::Seq { first: 0, n, wide }),
        ("offsets", Block::Seq { first: 1, n, wide }),
        ("types", Block::U8Const { value: 1, n }), // VTK_VERTEX
    ];

    let mut offset = 0u64;
    let mut array = |name: &str, b: &Block| -> String {
        let s = format!(
            "        <DataArray type=\"{}\" Name=\"{}\" NumberOfComponents=\"{}\" format=\"appended\" offset=\"{}\"/>\n",
            b.vtk_type(),
            name,
            b.components(),
            offset
        );
        offset += 8 + b.bytes();
        s
    };
    let mut xml = String::new();
    xml.push_str("<?xml version=\"1.0\"?>\n");
    xml.push_str("<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt64\">\n");
    xml.push_str("  <UnstructuredGrid>\n");
    xml.push_str(&format!(
        "    <Piece NumberOfPoints=\"{n}\" NumberOfCells=\"{n}\">\n"
    ));
    xml.push_str("      <PointData Scalars=\"radius\">\n");
    for (name, b) in &point_data {
        xml.push_str(&array(name, b));
    }
    xml.push_str("      </PointData>\n      <Points>\n");
    xml.push_str(&array("Points", &points));
    xml.push_str("      </Points>\n      <Cells>\n");
    for (name, b) in &cells {
        xml.push_str(&array(name, b));
    }
    xml.push_str("      </Cells>\n    </Piece>\n  </UnstructuredGrid>\n");
    xml.push_str("  <AppendedData encoding=\"raw\">\n   _");
    let tail = "\n  </AppendedData>\n</VTKFile>\n";
    let total = xml.len() as u64 + offset + tail.len() as u64;

    write_atomic(path.as_ref(), |w| {
        w.write_all(xml.as_bytes())?;
        for (_, b) in &point_data {
            b.write(w)?;
        }
        points.write(w)?;
        for (_, b) in &cells {
            b.write(w)?;
        }
        w.write_all(tail.as_bytes())
    })?;
    Ok(total)
}
