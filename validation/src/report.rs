//! Writes `<case>.json` for each case and `REPORT.md` gathering every case (DESIGN.md §3).

use std::fmt::Write as _;
use std::path::Path;

use anyhow::{Context, Result};

use crate::outcome::{CaseOutcome, fmt_sig};

/// Writes `bytes` to `path` atomically (temporary file in the same folder, then rename).
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<()> {
    let tmp = path.with_extension(format!(
        "{}.tmp",
        path.extension().and_then(|e| e.to_str()).unwrap_or("out")
    ));
    std::fs::write(&tmp, bytes).with_context(|| format!("writing {}", tmp.display()))?;
    std::fs::rename(&tmp, path)
        .with_context(|| format!("renaming {} to {}", tmp.display(), path.display()))?;
    Ok(())
}

/// Writes one case's JSON file, `<out>/<case>.json`.
pub fn write_case_json(out: &Path, outcome: &CaseOutcome) -> Result<()> {
    let json = serde_json::to_vec_pretty(outcome)?;
    write_atomic(&out.join(format!("{}.json", outcome.case)), &json)
}

fn json_cell(v: &serde_json::Value) -> String {
    match v {
        serde_json::Value::Number(n) => n.as_f64().map(fmt_sig).unwrap_or_else(|| n.to_string()),
        serde_json::Value::Object(m) => m
            .iter()
            .map(|(k, v)| format!("{k}: {}", json_cell(v)))
            .collect::<Vec<_>>()
            .join(", "),
        serde_json::Value::String(s) => s.clone(),
        other => other.to_string(),
    }
}

/// Renders the whole report as Markdown.
pub fn render_report(outcomes: &[CaseOutcome], header: &str) -> String {
    let mut s = String::new();
    let _ = writeln!(s, "# demcon validation report\n\n{header}\n");
    let _ = writeln!(
        s,
        "| case | mode | N (largest) | wall (s) | pass |\n|---|---|---|---|---|"
    );
    for o in outcomes {
        let _ = writeln!(
            s,
            "| [{0}](#{0}) | {1} | {2} | {3:.1} | {4} |",
            o.case,
            o.mode.name(),
            o.n_particles,
            o.wall_s,
            if o.pass { "yes" } else { "**NO**" }
        );
    }
    for o in outcomes {
        let _ = writeln!(s, "\n## {}\n", o.case);
        let _ = writeln!(
            s,
            "Mode `{}`, largest N = {}, wall time {:.1} s.\n",
            o.mode.name(),
            o.n_particles,
            o.wall_s
        );
        if !o.metrics.is_empty() {
            let _ = writeln!(s, "| metric | ours | reference |\n|---|---|---|");
            for (k, v) in &o.metrics {
                let r = o.reference.get(k).map(json_cell).unwrap_or_default();
                let _ = writeln!(s, "| `{k}` | {} | {r} |", json_cell(v));
            }
            if let Some(src) = o.reference.get("source") {
                let _ = writeln!(s, "\nReference source: {}", json_cell(src));
            }
        }
        if !o.comparisons.is_empty() {
            let _ = writeln!(
                s,
                "\n| check | measured | reference | tolerance | source | pass |\n|---|---|---|---|---|---|"
            );
            for c in &o.comparisons {
                let tol = if c.tolerance == 0.0 {
                    "≤ reference".to_string()
                } else if c.relative {
                    format!("{:.2} %", 100.0 * c.tolerance)
                } else {
                    fmt_sig(c.tolerance)
                };
                let _ = writeln!(
                    s,
                    "| {} | {} | {} | {} | {} | {} |",
                    c.name,
                    fmt_sig(c.measured),
                    fmt_sig(c.reference),
                    tol,
                    c.source,
                    if c.pass { "yes" } else { "**NO**" }
                );
            }
        }
        for t in &o.tables {
            let _ = writeln!(s, "\n**{}**\n", t.title);
            let _ = writeln!(s, "| {} |", t.header.join(" | "));
            let _ = writeln!(s, "|{}", "---|".repeat(t.header.len()));
            for r in &t.rows {
                let _ = writeln!(s, "| {} |", r.join(" | "));
            }
        }
        for n in &o.notes {
            let _ = writeln!(s, "\n- {n}");
        }
        for c in &o.charts {
            let _ = writeln!(s, "\n![{c}]({c})");
        }
    }
    s
}
