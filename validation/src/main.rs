//! `validate`: runs the validation cases and writes JSON, charts and REPORT.md.
//! Usually called as `cargo xtask validate [CASE…] [--quick | --full] [--out DIR]`.

use std::path::PathBuf;
use std::time::Instant;

use anyhow::{Context, Result, bail};
use clap::Parser;
use validation::{Ctx, Mode, cases, report};

#[derive(Parser, Debug)]
#[command(
    name = "validate",
    about = "Run demcon's validation cases (papers' cases vs analytic/FEM/FFT references)"
)]
struct Args {
    /// Case ids to run (default: all). `--list` shows them.
    cases: Vec<String>,
    /// Small sizes for CI (the default).
    #[arg(long, conflicts_with = "full")]
    quick: bool,
    /// The papers' particle counts (slow: run by hand).
    #[arg(long)]
    full: bool,
    /// Output folder.
    #[arg(long, default_value = "target/validation")]
    out: PathBuf,
    /// Base seed of the packings.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// List the cases and exit.
    #[arg(long)]
    list: bool,
}

fn main() -> Result<()> {
    let args = Args::parse();
    let registry = cases::registry();
    if args.list {
        for c in &registry {
            println!("{:<26} {}", c.id, c.about);
        }
        return Ok(());
    }
    for name in &args.cases {
        if !registry.iter().any(|c| c.id == name) {
            let ids: Vec<&str> = registry.iter().map(|c| c.id).collect();
            bail!("unknown case `{name}`; known cases: {}", ids.join(", "));
        }
    }
    let mode = if args.full { Mode::Full } else { Mode::Quick };
    std::fs::create_dir_all(&args.out).with_context(|| format!("creating {}", args.out.display()))?;
    let ctx = Ctx {
        mode,
        out: args.out.clone(),
        seed: args.seed,
    };
    let mut outcomes = Vec::new();
    let mut failed = Vec::new();
    for case in registry
        .iter()
        .filter(|c| args.cases.is_empty() || args.cases.iter().any(|n| n == c.id))
    {
        eprintln!("== {} ({})", case.id, case.about);
        let t0 = Instant::now();
        match (case.run)(&ctx) {
            Ok(mut o) => {
                o.wall_s = t0.elapsed().as_secs_f64();
                report::write_case_json(&args.out, &o)?;
                eprintln!("   {} in {:.1} s", if o.pass { "pass" } else { "FAIL" }, o.wall_s);
                if !o.pass {
                    failed.push(case.id.to_string());
                }
                outcomes.push(o);
            }
            Err(e) => {
                eprintln!("   ERROR: {e:#}");
                failed.push(format!("{} (error: {e:#})", case.id));
            }
        }
    }
    let (made, reused, saved_s) = cases::common::packing_cache_stats();
    eprintln!("packings: {made} made, {reused} reused ({saved_s:.0} s of packing saved)");
    let header = format!(
        "Mode `{}`, seed {}, {} case(s). Regenerate with `cargo xtask validate{}`. Every number below \
         is measured by this run; references come from `validation/data/` and `shared/refs/analytic.md`. \
         Packings: {made} made, {reused} reused by later scenes with the same packing section and seed \
         (a packing is a pure function of both; {saved_s:.0} s of packing saved; the packing times in \
         the tables are the cost of making each packing).",
        mode.name(),
        args.seed,
        outcomes.len(),
        if args.full { " --full" } else { " --quick" }
    );
    let md = report::render_report(&outcomes, &header);
    report::write_atomic(&args.out.join("REPORT.md"), md.as_bytes())?;
    eprintln!("report: {}", args.out.join("REPORT.md").display());
    if !failed.is_empty() {
        bail!("{} case(s) failed: {}", failed.len(), failed.join("; "));
    }
    Ok(())
}
