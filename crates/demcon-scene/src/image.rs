//! Phases from a labelled 3-D image: `.npy` (numpy, axes x, y, z), multi-page TIFF (one page a
//! z-slice, x along the rows) or raw (`dims` and `dtype` given, x fastest, little-endian), its
//! voxel size and origin, and a label → material map. Each mapped label becomes a region of its
//! voxels ([`demcon_core::Voxels`]); every refusal names the file or field, the value and what
//! is allowed.

use std::path::Path;

use demcon_core::{Aabb, Container, Vec3, Voxels};

use crate::error::SceneError;

/// A labelled image read from a file: labels per voxel, x fastest.
#[derive(Debug, Clone, PartialEq)]
pub struct LabelImage {
    /// Voxels along x, y, z.
    pub dims: [usize; 3],
    /// The label of each voxel (x fastest, then y, then z).
    pub labels: Vec<i64>,
}

/// The element types a raw file may hold.
const RAW_TYPES: &str = "u8, u16, u32, i8, i16, i32";

fn io(path: &Path, source: std::io::Error) -> SceneError {
    SceneError::Io {
        path: path.to_path_buf(),
        source,
    }
}

/// Reads the image at `path`: by its extension `.npy`, `.tif`/`.tiff`, or `.raw` (then `dims`
/// and `dtype` are needed). Refusals name `field`.
pub fn read_image(
    path: &Path,
    dims: Option<(usize, usize, usize)>,
    dtype: Option<&str>,
    field: &str,
) -> Result<LabelImage, SceneError> {
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase)
        .unwrap_or_default();
    match ext.as_str() {
        "npy" => read_npy(path, field),
        "tif" | "tiff" => read_tiff(path, field),
        "raw" => {
            let (Some(d), Some(t)) = (dims, dtype) else {
                return Err(SceneError::invalid(
                    &format!("{field}.dims"),
                    format!("{dims:?}, dtype {dtype:?}"),
                    "a raw image needs `dims: Some((nx, ny, nz))` and `dtype: Some(\"u8\")` (or u16, u32, i8, i16, i32)",
                ));
            };
            read_raw(path, [d.0, d.1, d.2], t, field)
        }
        other => Err(SceneError::invalid(
            &format!("{field}.path"),
            format!("{} (extension `{other}`)", path.display()),
            "an image file: .npy, .tif/.tiff (multi-page, one page per z-slice) or .raw",
        )),
    }
}

/// A raw file of `dims` voxels of `dtype`, x fastest, little-endian.
fn read_raw(path: &Path, dims: [usize; 3], dtype: &str, field: &str) -> Result<LabelImage, SceneError> {
    let width = match dtype {
        "u8" | "i8" => 1,
        "u16" | "i16" => 2,
        "u32" | "i32" => 4,
        _ => {
            return Err(SceneError::invalid(
                &format!("{field}.dtype"),
                format!("\"{dtype}\""),
                format!("one of {RAW_TYPES}"),
            ));
        }
    };
    let n: usize = dims.iter().product();
    if n == 0 {
        return Err(SceneError::invalid(
            &format!("{field}.dims"),
            format!("{dims:?}"),
            "three sizes ≥ 1",
        ));
    }
    let bytes = std::fs::read(path).map_err(|e| io(path, e))?;
    if bytes.len() != n * width {
        return Err(SceneError::invalid(
            &format!("{field}.path"),
            format!("{} ({} bytes)", path.display(), bytes.len()),
            format!(
                "{} × {} × {} voxels of {dtype} are {} bytes: the file is truncated, or `dims`/`dtype` are not its own",
                dims[0],
                dims[1],
                dims[2],
                n * width
            ),
        ));
    }
    let labels = bytes
        .chunks_exact(width)
        .map(|c| match dtype {
            "u8" => i64::from(c[0]),
            "i8" => i64::from(c[0] as i8),
            "u16" => i64::from(u16::from_le_bytes([c[0], c[1]])),
            "i16" => i64::from(i16::from_le_bytes([c[0], c[1]])),
            "u32" => i64::from(u32::from_le_bytes([c[0], c[1], c[2], c[3]])),
            _ => i64::from(i32::from_le_bytes([c[0], c[1], c[2], c[3]])),
        })
        .collect();
    Ok(LabelImage { dims, labels })
}

/// A `.npy` array of three axes (x, y, z) of integers, C or Fortran order.
fn read_npy(path: &Path, field: &str) -> Result<LabelImage, SceneError> {
    let bytes = std::fs::read(path).map_err(|e| io(path, e))?;
    let bad = |why: String| SceneError::invalid(&format!("{field}.path"), path.display(), why);
    let npy = npyz::NpyFile::new(&bytes[..]).map_err(|e| bad(format!("not a readable .npy file: {e}")))?;
    let shape: Vec<usize> = npy.shape().iter().map(|&s| s as usize).collect();
    let [nx, ny, nz] = shape[..] else {
        return Err(bad(format!(
            "an array of shape {shape:?}: a 3-D array (x, y, z) is needed"
        )));
    };
    let fortran = npy.order() == npyz::Order::Fortran;
    let descr = npy.dtype().descr();
    let flat: Vec<i64> = match descr
        .trim_matches(['\'', '"'])
        .trim_start_matches(['<', '>', '|', '='])
    {
        "u1" => npy
            .into_vec::<u8>()
            .map(|v| v.into_iter().map(i64::from).collect()),
        "i1" => npy
            .into_vec::<i8>()
            .map(|v| v.into_iter().map(i64::from).collect()),
        "u2" => npy
            .into_vec::<u16>()
            .map(|v| v.into_iter().map(i64::from).collect()),
        "i2" => npy
            .into_vec::<i16>()
            .map(|v| v.into_iter().map(i64::from).collect()),
        "u4" => npy
            .into_vec::<u32>()
            .map(|v| v.into_iter().map(i64::from).collect()),
        "i4" => npy
            .into_vec::<i32>()
            .map(|v| v.into_iter().map(i64::from).collect()),
        "i8" => npy.into_vec::<i64>(),
        "b1" => npy
            .into_vec::<bool>()
            .map(|v| v.into_iter().map(i64::from).collect()),
        other => {
            return Err(bad(format!(
                "elements of type `{other}`: labels are integers (u1, u2, u4, i1, i2, i4, i8, or bool)"
            )));
        }
    }
    .map_err(|e| bad(format!("truncated or unreadable data: {e}")))?;
    // Reorder to x fastest: C order has z fastest, Fortran x.
    let labels = if fortran {
        flat
    } else {
        let mut out = vec![0; flat.len()];
        for x in 0..nx {
            for y in 0..ny {
                for z in 0..nz {
                    out[(z * ny + y) * nx + x] = flat[(x * ny + y) * nz + z];
                }
            }
        }
        out
    };
    Ok(LabelImage {
        dims: [nx, ny, nz],
        labels,
    })
}

/// A multi-page grey-level TIFF of integer samples: each page a z-slice (rows along y, x along
/// a row), all pages of one size.
fn read_tiff(path: &Path, field: &str) -> Result<LabelImage, SceneError> {
    use tiff::decoder::{Decoder, DecodingResult};
    let file = std::fs::File::open(path).map_err(|e| io(path, e))?;
    let bad = |why: String| SceneError::invalid(&format!("{field}.path"), path.display(), why);
    let mut dec =
        Decoder::new(std::io::BufReader::new(file)).map_err(|e| bad(format!("not a readable TIFF: {e}")))?;
    let mut labels = Vec::new();
    let mut size = None;
    let mut pages = 0;
    loop {
        let color = dec.colortype().map_err(|e| bad(format!("page {pages}: {e}")))?;
        if !matches!(color, tiff::ColorType::Gray(_)) {
            return Err(bad(format!(
                "page {pages} is {color:?}: a label image is one grey channel of integers"
            )));
        }
        let dims = dec.dimensions().map_err(|e| bad(format!("page {pages}: {e}")))?;
        if size.is_some_and(|s| s != dims) {
            return Err(bad(format!(
                "page {pages} is {} × {}, page 0 {:?}: every page must have the same size",
                dims.0,
                dims.1,
                size.unwrap_or_default()
            )));
        }
        size = Some(dims);
        let page = dec.read_image().map_err(|e| bad(format!("page {pages}: {e}")))?;
        match page {
            DecodingResult::U8(v) => labels.extend(v.into_iter().map(i64::from)),
            DecodingResult::U16(v) => labels.extend(v.into_iter().map(i64::from)),
            DecodingResult::U32(v) => labels.extend(v.into_iter().map(i64::from)),
            DecodingResult::I8(v) => labels.extend(v.into_iter().map(i64::from)),
            DecodingResult::I16(v) => labels.extend(v.into_iter().map(i64::from)),
            DecodingResult::I32(v) => labels.extend(v.into_iter().map(i64::from)),
            _ => {
                return Err(bad(format!(
                    "page {pages} holds floating-point or 64-bit samples: labels are 8-, 16- or 32-bit integers"
                )));
            }
        }
        pages += 1;
        if !dec.more_images() {
            break;
        }
        dec.next_image().map_err(|e| bad(format!("page {pages}: {e}")))?;
    }
    let (w, h) = size.unwrap_or_default();
    Ok(LabelImage {
        dims: [w as usize, h as usize, pages],
        labels,
    })
}

/// The regions of an image's mapped labels present in it, in the order of `map`, after
/// checking that every label in the image has a material (refusals name `field`); `periodic`
/// when the image is the period of a periodic box.
pub fn label_regions(
    image: &LabelImage,
    voxel: f64,
    origin: Vec3,
    map: &[(i64, u16)],
    periodic: bool,
    field: &str,
) -> Result<Vec<(u16, Voxels)>, SceneError> {
    let mut present: Vec<i64> = image.labels.clone();
    present.sort_unstable();
    present.dedup();
    let unmapped: Vec<String> = present
        .iter()
        .filter(|l| !map.iter().any(|(m, _)| m == *l))
        .take(10)
        .map(i64::to_string)
        .collect();
    if !unmapped.is_empty() {
        return Err(SceneError::invalid(
            &format!("{field}.labels"),
            format!("labels {} in the image have no material", unmapped.join(", ")),
            "map every label of the image to a material (the matrix too)",
        ));
    }
    map.iter()
        .filter(|(label, _)| present.binary_search(label).is_ok())
        .map(|&(label, phase)| {
            let mask: Vec<bool> = image.labels.iter().map(|&l| l == label).collect();
            Ok((
                phase,
                Voxels::from_mask(image.dims, voxel, origin, &mask, periodic, field)?,
            ))
        })
        .collect()
}

/// Refuses an image (box `image`, m) that does not cover the container's box — in a periodic
/// box, that is not exactly its period — naming `field`.
pub fn check_covers(image: &Aabb, container: &Container, field: &str) -> Result<(), SceneError> {
    let b = container.bounds();
    let tol = 1e-9 * (image.max - image.min).max();
    let exact = container.period().is_some();
    let off = |i: usize| {
        let (lo, hi) = (image.min[i] - b.min[i], image.max[i] - b.max[i]);
        if exact {
            lo.abs() > tol || hi.abs() > tol
        } else {
            lo > tol || hi < -tol
        }
    };
    if (0..3).any(off) {
        return Err(SceneError::invalid(
            &format!("{field}.origin"),
            format!(
                "the image spans [{:e}, {:e}] × [{:e}, {:e}] × [{:e}, {:e}] m",
                image.min.x, image.max.x, image.min.y, image.max.y, image.min.z, image.max.z
            ),
            format!(
                "an image covering the container's box [{:e}, {:e}] × [{:e}, {:e}] × [{:e}, {:e}] m, exactly in a \
                 periodic box (check `voxel`, `origin` and the image's size)",
                b.min.x, b.max.x, b.min.y, b.max.y, b.min.z, b.max.z
            ),
        ));
    }
    Ok(())
}
