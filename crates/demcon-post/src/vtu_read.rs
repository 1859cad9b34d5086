//! Reads back a `.vtu` file in the format [`crate::write_vtu`] writes (VTK XML
//! `UnstructuredGrid`, little-endian, raw appended data with UInt64 block headers): the points
//! and every point-data array, as `f64`. Not a general VTK reader: other encodings (base64,
//! compressed, UInt32 headers) are refused with a message saying so.

use std::path::Path;

use demcon_core::Vec3;

use crate::error::PostError;

/// One point-data array of a `.vtu` file.
#[derive(Debug, Clone, PartialEq)]
pub struct VtuArray {
    /// Its name (`temperature`, `halo_flux`, …).
    pub name: String,
    /// Components per point (1 for a scalar, 3 for a vector).
    pub components: usize,
    /// The values, point by point (`components` per point), converted to `f64`.
    pub values: Vec<f64>,
}

impl VtuArray {
    /// The value of each point: the value itself for a scalar, the Euclidean norm of the
    /// components for a vector.
    pub fn magnitudes(&self) -> Vec<f64> {
        if self.components == 1 {
            return self.values.clone();
        }
        self.values
            .chunks(self.components.max(1))
            .map(|c| c.iter().map(|x| x * x).sum::<f64>().sqrt())
            .collect()
    }
}

/// The contents of a `.vtu` file read by [`read_vtu`].
#[derive(Debug, Clone, PartialEq)]
pub struct VtuData {
    /// The points (m).
    pub points: Vec<Vec3>,
    /// The point-data arrays, in file order.
    pub arrays: Vec<VtuArray>,
}

impl VtuData {
    /// The array called `name`, if any.
    pub fn array(&self, name: &str) -> Option<&VtuArray> {
        self.arrays.iter().find(|a| a.name == name)
    }
}

/// One `<DataArray …/>` declaration of the XML header.
struct Decl {
    name: String,
    ty: String,
    components: usize,
    offset: usize,
    in_points: bool,
}

/// The value of `key="…"` in an XML tag, if present.
fn attribute<'a>(tag: &'a str, key: &str) -> Option<&'a str> {
    let pat = format!(" {key}=\"");
    let start = tag.find(&pat)? + pat.len();
    let len = tag[start..].find('"')?;
    Some(&tag[start..start + len])
}

fn unescape(s: &str) -> String {
    s.replace("&lt;", "<")
        .replace("&gt;", ">")
        .replace("&quot;", "\"")
        .replace("&apos;", "'")
        .replace("&amp;", "&")
}

/// Reads a `.vtu` file written by [`crate::write_vtu`]. Errors: the file cannot be read, or
/// it is not in that format (the message says what differs), or a block is truncated.
pub fn read_vtu(path: impl AsRef<Path>) -> Result<VtuData, PostError> {
    let path = path.as_ref();
    let bytes = std::fs::read(path).map_err(|source| PostError::Io {
        action: "reading",
        path: path.to_path_buf(),
        source,
    })?;
    let format = |message: String| PostError::Format {
        path: path.to_path_buf(),
        line: 1,
        message,
    };
    const MARK: &[u8] = b"<AppendedData encoding=\"raw\">";
    let Some(at) = bytes.windows(MARK.len()).position(|w| w == MARK) else {
        return Err(format(
            "no raw appended data: only the .vtu files demcon writes (raw appended binary) are read".into(),
        ));
    };
    let head = std::str::from_utf8(&bytes[..at]).map_err(|_| format("the XML header is not UTF-8".into()))?;
    let Some(root) = head.find("<VTKFile").map(|i| &head[i..]) else {
        return Err(format("no <VTKFile> element: not a VTK XML file".into()));
    };
    let root_tag = &root[..root.find('>').unwrap_or(root.len())];
    for (key, want) in [
        ("type", "UnstructuredGrid"),
        ("byte_order", "LittleEndian"),
        ("header_type", "UInt64"),
    ] {
        let got = attribute(root_tag, key).unwrap_or("(none)");
        if got != want {
            return Err(format(format!(
                "{key} is {got}, expected {want} (the format demcon writes)"
            )));
        }
    }
    let n: usize = head
        .find("<Piece")
        .and_then(|i| attribute(&head[i..], "NumberOfPoints"))
        .and_then(|s| s.parse().ok())
        .ok_or_else(|| format("no <Piece NumberOfPoints=…>".into()))?;
    // The declarations, and whether each is in <Points>.
    let mut decls = Vec::new();
    let mut rest = head;
    while let Some(i) = rest.find("<DataArray") {
        let before = &head[..head.len() - rest.len() + i];
        let in_points = before.rfind("<Points>") > before.rfind("</Points>");
        let tag_end = rest[i..].find('>').map_or(rest.len(), |e| i + e);
        let tag = &rest[i..tag_end];
        let get = |k: &str| attribute(tag, k).ok_or_else(|| format(format!("a DataArray without {k}")));
        if get("format")? != "appended" {
            return Err(format(format!(
                "DataArray {} is not in the appended block",
                get("Name")?
            )));
        }
        decls.push(Decl {
            name: unescape(get("Name")?),
            ty: get("type")?.to_string(),
            components: attribute(tag, "NumberOfComponents")
                .unwrap_or("1")
                .parse()
                .map_err(|_| format("a DataArray with a bad NumberOfComponents".into()))?,
            offset: get("offset")?
                .parse()
                .map_err(|_| format("a DataArray with a bad offset".into()))?,
            in_points,
        });
        rest = &rest[tag_end..];
    }
    // The appended data starts after the `_` that follows the marker.
    let data_start = bytes[at + MARK.len()..]
        .iter()
        .position(|&b| b == b'_')
        .map(|p| at + MARK.len() + p + 1)
        .ok_or_else(|| format("no `_` opening the appended data".into()))?;
    let data = &bytes[data_start..];
    let mut points = None;
    let mut arrays = Vec::new();
    for d in decls.iter().filter(|d| d.in_points || !is_cell_array(&d.name)) {
        let values = decode(data, d, n).map_err(|m| format(format!("array {}: {m}", d.name)))?;
        if d.in_points {
            if d.components != 3 {
                return Err(format("points with other than 3 components".into()));
            }
            points = Some(values.chunks(3).map(|c| Vec3::new(c[0], c[1], c[2])).collect());
        } else {
            arrays.push(VtuArray {
                name: d.name.clone(),
                components: d.components,
                values,
            });
        }
    }
    Ok(VtuData {
        points: points.ok_or_else(|| format("no <Points> array".into()))?,
        arrays,
    })
}

/// The cell arrays of our writer (vertex cells), which carry no field.
fn is_cell_array(name: &str) -> bool {
    matches!(name, "connectivity" | "offsets" | "types")
}

/// The `n · components` values of one block, converted to `f64`.
fn decode(data: &[u8], d: &Decl, n: usize) -> Result<Vec<f64>, String> {
    let header = data
        .get(d.offset..d.offset + 8)
        .ok_or("offset past the end of the file")?;
    let len = u64::from_le_bytes(header.try_into().expect("8 bytes")) as usize;
    let size = match d.ty.as_str() {
        "Float64" | "Int64" | "UInt64" => 8,
        "Float32" | "Int32" | "UInt32" => 4,
        "Int16" | "UInt16" => 2,
        "Int8" | "UInt8" => 1,
        t => return Err(format!("type {t} is not read")),
    };
    let count = n * d.components;
    if len != count * size {
        return Err(format!("{len} bytes, expected {count} values of {size} bytes"));
    }
    let block = data
        .get(d.offset + 8..d.offset + 8 + len)
        .ok_or("truncated block")?;
    let v = block.chunks_exact(size);
    Ok(match d.ty.as_str() {
        "Float64" => v.map(|c| f64::from_le_bytes(c.try_into().expect("8"))).collect(),
        "Int64" => v
            .map(|c| i64::from_le_bytes(c.try_into().expect("8")) as f64)
            .collect(),
        "UInt64" => v
            .map(|c| u64::from_le_bytes(c.try_into().expect("8")) as f64)
            .collect(),
        "Float32" => v
            .map(|c| f32::from_le_bytes(c.try_into().expect("4")) as f64)
            .collect(),
        "Int32" => v
            .map(|c| i32::from_le_bytes(c.try_into().expect("4")) as f64)
            .collect(),
        "UInt32" => v
            .map(|c| u32::from_le_bytes(c.try_into().expect("4")) as f64)
            .collect(),
        "Int16" => v
            .map(|c| i16::from_le_bytes(c.try_into().expect("2")) as f64)
            .collect(),
        "UInt16" => v
            .map(|c| u16::from_le_bytes(c.try_into().expect("2")) as f64)
            .collect(),
        "Int8" => v.map(|c| c[0] as i8 as f64).collect(),
        _ => v.map(|c| c[0] as f64).collect(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{Field, write_vtu};
    use demcon_core::ParticleSet;

    #[test]
    fn what_write_vtu_writes_reads_back() {
        let dir = std::env::temp_dir().join(format!("demcon-post-vtu-read-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("p.vtu");
        let centres = vec![
            Vec3::new(0.1, 0.2, 0.3),
            Vec3::new(1.0, 2.0, 3.0),
            Vec3::new(-1.0, 0.5, 2.5),
        ];
        let p = ParticleSet::new(centres.clone(), vec![0.1, 0.2, 0.3]).unwrap();
        let t = [25.0, 30.5, 35.0];
        let q = [Vec3::new(3.0, 4.0, 0.0), Vec3::zeros(), Vec3::new(0.0, 0.0, -2.0)];
        let k = [1, 0, 1];
        write_vtu(
            &path,
            &p,
            &[
                Field::scalars("temperature", &t),
                Field::vectors("halo_flux", &q),
                Field::ints("solved", &k),
                Field::scalars("a<b", &t),
            ],
        )
        .unwrap();
        let d = read_vtu(&path).unwrap();
        assert_eq!(d.points, centres);
        let names: Vec<&str> = d.arrays.iter().map(|a| a.name.as_str()).collect();
        assert_eq!(
            names,
            ["radius", "phase", "temperature", "halo_flux", "solved", "a<b"]
        );
        assert_eq!(d.array("radius").unwrap().values, [0.1, 0.2, 0.3]);
        assert_eq!(d.array("temperature").unwrap().values, t);
        assert_eq!(d.array("solved").unwrap().values, [1.0, 0.0, 1.0]);
        assert_eq!(d.array("halo_flux").unwrap().magnitudes(), [5.0, 0.0, 2.0]);

        // Not our format: a clear refusal naming the file.
        let other = dir.join("ascii.vtu");
        std::fs::write(&other, "<VTKFile type=\"UnstructuredGrid\"></VTKFile>").unwrap();
        let e = read_vtu(&other).unwrap_err().to_string();
        assert!(e.contains("ascii.vtu") && e.contains("raw appended"), "{e}");
        // Truncated: refused, no panic.
        let bytes = std::fs::read(&path).unwrap();
        std::fs::write(&other, &bytes[..bytes.len() - 150]).unwrap();
        assert!(read_vtu(&other).is_err());
        let _ = std::fs::remove_dir_all(&dir);
    }
}
