//! CSV output of columns of numbers (and a reader for the same files), written atomically.

use std::io::Write;
use std::path::Path;

use crate::atomic::write_atomic;
use crate::error::PostError;

/// Quotes a header cell if it holds a comma, a quote or a line break.
fn quote(s: &str) -> String {
    if s.contains([',', '"', '\n', '\r']) {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s.to_string()
    }
}

/// Formats a finite number so that it reads back exactly: plain decimals for moderate
/// magnitudes, scientific notation otherwise.
fn number(v: f64) -> String {
    let a = v.abs();
    if a == 0.0 || (1e-4..1e15).contains(&a) {
        format!("{v}")
    } else {
        format!("{v:e}")
    }
}

/// Writes a CSV file: one header line (`header[j]` names `columns[j]`), then one line per
/// row, comma-separated, numbers printed so that they read back bit-exactly. Written
/// atomically (temporary file + rename).
///
/// Errors: header and columns of different counts, columns of different lengths, no column,
/// a non-finite number (named by column and row), or a file-system failure.
pub fn write_csv(path: impl AsRef<Path>, header: &[&str], columns: &[&[f64]]) -> Result<(), PostError> {
    if columns.is_empty() || header.len() != columns.len() {
        return Err(PostError::invalid(
            "header",
            format!("{} names for {} columns", header.len(), columns.len()),
            "one name per column, at least one column",
        ));
    }
    let rows = columns[0].len();
    for (j, c) in columns.iter().enumerate() {
        if c.len() != rows {
            return Err(PostError::invalid(
                format!("columns[{j}] ({})", header[j]),
                format!("{} rows", c.len()),
                format!("{rows} rows, like the first column"),
            ));
        }
        if let Some(i) = c.iter().position(|v| !v.is_finite()) {
            return Err(PostError::invalid(
                format!("columns[{j}] ({}) row {i}", header[j]),
                c[i],
                "must be finite",
            ));
        }
    }
    write_atomic(path.as_ref(), |w| {
        let head: Vec<String> = header.iter().map(|h| quote(h)).collect();
        writeln!(w, "{}", head.join(","))?;
        let mut line = String::new();
        for i in 0..rows {
            line.clear();
            for (j, c) in columns.iter().enumerate() {
                if j > 0 {
                    line.push(',');
                }
                line.push_str(&number(c[i]));
            }
            line.push('\n');
            w.write_all(line.as_bytes())?;
        }
        Ok(())
    })
}

/// Splits a header line, honouring double-quoted cells.
fn split_header(line: &str) -> Vec<String> {
    let mut cells = Vec::new();
    let mut cur = String::new();
    let mut quoted = false;
    let mut chars = line.chars().peekable();
    while let Some(ch) = chars.next() {
        match (ch, quoted) {
            ('"', true) if chars.peek() == Some(&'"') => {
                cur.push('"');
                chars.next();
            }
            ('"', _) => quoted = !quoted,
            (',', false) => cells.push(std::mem::take(&mut cur)),
            _ => cur.push(ch),
        }
    }
    cells.push(cur);
    cells
}

/// Reads a CSV file of numbers with one header line, as written by [`write_csv`]: the
/// column names and the columns.
pub fn read_csv(path: impl AsRef<Path>) -> Result<(Vec<String>, Vec<Vec<f64>>), PostError> {
    let path = path.as_ref();
    let text = std::fs::read_to_string(path).map_err(|source| PostError::Io {
        action: "reading",
        path: path.to_path_buf(),
        source,
    })?;
    let mut lines = text.lines();
    let format = |line: usize, message: String| PostError::Format {
        path: path.to_path_buf(),
        line,
        message,
    };
    let header = split_header(
        lines
            .next()
            .ok_or_else(|| format(1, "empty file, expected a header line".into()))?,
    );
    let mut columns = vec![Vec::new(); header.len()];
    for (n, line) in lines.enumerate() {
        if line.trim().is_empty() {
            continue;
        }
        let cells: Vec<&str> = line.split(',').collect();
        if cells.len() != header.len() {
            return Err(format(
                n + 2,
                format!("{} cells, expected {}", cells.len(), header.len()),
            ));
        }
        for (j, cell) in cells.iter().enumerate() {
            let v = cell
                .trim()
                .parse::<f64>()
                .map_err(|e| format(n + 2, format!("cell {} `{cell}`: {e}", j + 1)))?;
            columns[j].push(v);
        }
    }
    Ok((header, columns))
}
