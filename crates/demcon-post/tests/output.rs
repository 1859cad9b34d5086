//! Integration tests of the writers: the VTU file is parsed back (header XML, byte counts,
//! appended values) and the CSV file round-trips bit-exactly.

mod common;

use std::collections::HashMap;
use std::path::PathBuf;

use common::jittered;
use demcon_core::Vec3;
use demcon_post::*;

fn tmp(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("demcon-post-test-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir.join(name)
}

/// Value of `key="…"` in an XML tag.
fn attr<'a>(tag: &'a str, key: &str) -> Option<&'a str> {
    let pat = format!(" {key}=\"");
    let start = tag.find(&pat)? + pat.len();
    let len = tag[start..].find('"')?;
    Some(&tag[start..start + len])
}

/// A parsed DataArray: type, components, raw bytes.
struct Array {
    ty: String,
    comps: usize,
    bytes: Vec<u8>,
}

/// Parses a raw-appended VTU as written by `write_vtu`: number of points and every array.
fn parse_vtu(data: &[u8]) -> (usize, HashMap<String, Array>) {
    let marker = b"<AppendedData encoding=\"raw\">";
    let at = data
        .windows(marker.len())
        .position(|w| w == marker)
        .expect("AppendedData");
    let header = std::str::from_utf8(&data[..at]).expect("header is UTF-8");
    assert!(header.starts_with("<?xml version=\"1.0\"?>"));
    let vtk = header.lines().find(|l| l.contains("<VTKFile")).unwrap();
    assert_eq!(attr(vtk, "type"), Some("UnstructuredGrid"));
    assert_eq!(attr(vtk, "byte_order"), Some("LittleEndian"));
    assert_eq!(attr(vtk, "header_type"), Some("UInt64"));
    let piece = header.lines().find(|l| l.contains("<Piece")).unwrap();
    let n: usize = attr(piece, "NumberOfPoints").unwrap().parse().unwrap();
    assert_eq!(attr(piece, "NumberOfCells").unwrap(), n.to_string());
    // Well-formed nesting: every opened element is closed, in order.
    let mut stack: Vec<String> = Vec::new();
    for l in header
        .lines()
        .map(str::trim)
        .filter(|l| l.starts_with('<') && !l.starts_with("<?"))
    {
        let name: String = l
            .trim_start_matches(['<', '/'])
            .chars()
            .take_while(|c| c.is_alphanumeric())
            .collect();
        if l.starts_with("</") {
            assert_eq!(stack.pop().as_deref(), Some(name.as_str()));
        } else if !l.ends_with("/>") {
            stack.push(name);
        }
    }
    assert_eq!(
        stack,
        vec!["VTKFile".to_string()],
        "only VTKFile is open before the data"
    );
    let underscore = at + marker.len() + data[at + marker.len()..].iter().position(|&b| b == b'_').unwrap();
    let base = underscore + 1;
    let mut arrays = HashMap::new();
    let mut expected_offset = 0usize;
    for l in header.lines().filter(|l| l.contains("<DataArray")) {
        assert_eq!(attr(l, "format"), Some("appended"));
        let name = attr(l, "Name").unwrap().to_string();
        let ty = attr(l, "type").unwrap().to_string();
        let comps: usize = attr(l, "NumberOfComponents").unwrap().parse().unwrap();
        let offset: usize = attr(l, "offset").unwrap().parse().unwrap();
        assert_eq!(offset, expected_offset, "{name}: arrays are packed in order");
        let size = match ty.as_str() {
            "Float64" | "Int64" => 8,
            "Int32" => 4,
            "UInt16" => 2,
            "UInt8" => 1,
            t => panic!("unexpected type {t}"),
        };
        let count = u64::from_le_bytes(data[base + offset..base + offset + 8].try_into().unwrap()) as usize;
        assert_eq!(count, n * comps * size, "{name}: block byte count");
        let bytes = data[base + offset + 8..base + offset + 8 + count].to_vec();
        expected_offset = offset + 8 + count;
        arrays.insert(name, Array { ty, comps, bytes });
    }
    let tail = std::str::from_utf8(&data[base + expected_offset..]).unwrap();
    assert_eq!(tail, "\n  </AppendedData>\n</VTKFile>\n");
    (n, arrays)
}

fn f64s(b: &[u8]) -> Vec<f64> {
    b.chunks(8)
        .map(|c| f64::from_le_bytes(c.try_into().unwrap()))
        .collect()
}

#[test]
fn vtu_is_well_formed_and_reads_back() {
    let mut p = jittered(5, 11);
    for (i, ph) in p.phases.iter_mut().enumerate() {
        *ph = (i % 3) as u16;
    }
    let t: Vec<f64> = p.centres.iter().map(|c| 20.0 + c.x * 1e-3).collect();
    let q: Vec<Vec3> = p
        .centres
        .iter()
        .map(|c| Vec3::new(-c.y, 1e300, -1e-300))
        .collect();
    let flag: Vec<i32> = (0..p.len() as i32).map(|i| i % 2 - 1).collect();
    let path = tmp("p.vtu");
    let fields = [
        Field::scalars("temperature", &t),
        Field::vectors("flux \"halo\" <k=11>", &q),
        Field::ints("truncated", &flag),
    ];
    let written = write_vtu(&path, &p, &fields).unwrap();
    let data = std::fs::read(&path).unwrap();
    assert_eq!(written as usize, data.len());
    let (n, arrays) = parse_vtu(&data);
    assert_eq!(n, p.len());
    assert_eq!(f64s(&arrays["radius"].bytes), p.radii);
    let phases: Vec<u16> = arrays["phase"]
        .bytes
        .chunks(2)
        .map(|c| u16::from_le_bytes([c[0], c[1]]))
        .collect();
    assert_eq!(phases, p.phases);
    assert_eq!(f64s(&arrays["temperature"].bytes), t);
    let fl = &arrays["flux &quot;halo&quot; &lt;k=11&gt;"];
    assert_eq!((fl.ty.as_str(), fl.comps), ("Float64", 3));
    let back: Vec<f64> = f64s(&fl.bytes);
    let want: Vec<f64> = q.iter().flat_map(|v| [v.x, v.y, v.z]).collect();
    assert_eq!(back, want);
    let flags: Vec<i32> = arrays["truncated"]
        .bytes
        .chunks(4)
        .map(|c| i32::from_le_bytes(c.try_into().unwrap()))
        .collect();
    assert_eq!(flags, flag);
    let pts = f64s(&arrays["Points"].bytes);
    assert_eq!(
        pts,
        p.centres.iter().flat_map(|v| [v.x, v.y, v.z]).collect::<Vec<_>>()
    );
    let conn: Vec<i32> = arrays["connectivity"]
        .bytes
        .chunks(4)
        .map(|c| i32::from_le_bytes(c.try_into().unwrap()))
        .collect();
    assert_eq!(conn, (0..n as i32).collect::<Vec<_>>());
    let offs: Vec<i32> = arrays["offsets"]
        .bytes
        .chunks(4)
        .map(|c| i32::from_le_bytes(c.try_into().unwrap()))
        .collect();
    assert_eq!(offs, (1..=n as i32).collect::<Vec<_>>());
    assert!(arrays["types"].bytes.iter().all(|&b| b == 1));
    // No temporary file is left beside it.
    let left: Vec<_> = std::fs::read_dir(path.parent().unwrap())
        .unwrap()
        .filter_map(|e| e.ok())
        .filter(|e| e.file_name().to_string_lossy().contains(".tmp"))
        .collect();
    assert!(left.is_empty());
    std::fs::remove_file(&path).unwrap();
}

#[test]
fn vtu_rejects_bad_fields_and_leaves_no_file() {
    let p = jittered(3, 1);
    let t = vec![1.0; p.len() - 1];
    let path = tmp("bad.vtu");
    let e = write_vtu(&path, &p, &[Field::scalars("T", &t)]).unwrap_err();
    assert!(e.to_string().contains("field T"), "{e}");
    assert!(!path.exists());
    let mut t = vec![1.0; p.len()];
    t[4] = f64::NAN;
    let e = write_vtu(&path, &p, &[Field::scalars("T", &t)]).unwrap_err();
    assert!(e.to_string().contains("T[4]"), "{e}");
    let ok = vec![1.0; p.len()];
    assert!(write_vtu(&path, &p, &[Field::scalars("radius", &ok)]).is_err());
    assert!(write_vtu(&path, &p, &[Field::scalars("a", &ok), Field::scalars("a", &ok)]).is_err());
    let e = write_vtu(tmp("no/such/dir/x.vtu"), &p, &[]).unwrap_err();
    assert!(matches!(e, PostError::Io { .. }), "{e}");
}

#[test]
fn csv_round_trip_is_exact() {
    let a = vec![0.0, -0.0, 1.0 / 3.0, 1e-300, -2.5e20, 123456.789, 5e-324];
    let b = vec![1.0, 2.0, 3.0, 4.0, 5.0, 6.0, f64::MAX];
    let path = tmp("cols.csv");
    write_csv(&path, &["s (m)", "T, \"K\""], &[&a, &b]).unwrap();
    let (h, cols) = read_csv(&path).unwrap();
    assert_eq!(h, vec!["s (m)".to_string(), "T, \"K\"".to_string()]);
    assert_eq!(cols.len(), 2);
    for (x, y) in cols[0].iter().zip(&a) {
        assert_eq!(x.to_bits(), y.to_bits());
    }
    assert_eq!(cols[1], b);
    let text = std::fs::read_to_string(&path).unwrap();
    assert!(text.lines().nth(1).unwrap().starts_with("0,1"), "{text}");
    std::fs::remove_file(&path).unwrap();
}

#[test]
fn csv_errors() {
    let path = tmp("e.csv");
    let e = write_csv(&path, &["a"], &[&[1.0], &[2.0]]).unwrap_err();
    assert!(e.to_string().contains("header"), "{e}");
    let e = write_csv(&path, &["a", "b"], &[&[1.0], &[2.0, 3.0]]).unwrap_err();
    assert!(e.to_string().contains("columns[1]"), "{e}");
    let e = write_csv(&path, &["a"], &[&[1.0, f64::INFINITY]]).unwrap_err();
    assert!(e.to_string().contains("row 1"), "{e}");
    assert!(!path.exists());
    std::fs::write(&path, "a,b\n1,2\n3\n").unwrap();
    let e = read_csv(&path).unwrap_err();
    assert!(matches!(e, PostError::Format { line: 3, .. }), "{e}");
    std::fs::remove_file(&path).unwrap();
}
