//! `packing-stress` — the packer's guarantee on many small packings (robustness issue): every
//! packing finishes without error (target reached, jammed, or a budget stop) with no overlap above `MAX_OVERLAP` = 1e-9 of
//! the smaller radius, over seeds, the four containers and growth rates from 0.005 to 1.
//!
//! Not a paper case: it guards the Lubachevsky–Stillinger engine every other case relies on.
//! The tolerance is the packer's own contract (1e-9 R), fixed before any run; before the
//! symmetric initial neighbour lists, 295 of 1000 such packings broke it (`docs/packing.md`).
//! Quick: 200 packings; full: 1000 (about 15 ms each in release).

use demcon_packing::{MAX_OVERLAP, STRESS_GROWTH_RATES, StressReport, stress_packings};

use crate::{CaseOutcome, Comparison, Ctx};

/// Runs the case.
pub fn run(ctx: &Ctx) -> anyhow::Result<CaseOutcome> {
    let rep = measure(ctx);
    let mut out = CaseOutcome::new("packing-stress", ctx.mode);
    compare(&rep, &mut out);
    report(&rep, &mut out);
    Ok(out)
}

/// The sweep: `cases` small packings.
fn measure(ctx: &Ctx) -> StressReport {
    stress_packings(ctx.pick(200, 1000))
}

fn compare(rep: &StressReport, out: &mut CaseOutcome) {
    out.compare(Comparison::at_most(
        "largest overlap / smaller radius",
        rep.worst_overlap,
        MAX_OVERLAP,
        "the packer's contract (no overlap > 1e-9 R)",
    ));
    out.compare(Comparison::at_most(
        "failed packings",
        rep.failures.len() as f64,
        0.0,
        "every packing finishes without error",
    ));
}

fn report(rep: &StressReport, out: &mut CaseOutcome) {
    out.metric("cases", rep.cases as f64);
    out.metric("reached", rep.reached as f64);
    out.metric("jammed", rep.jammed as f64);
    out.metric("worst_overlap", rep.worst_overlap);
    out.metric("failures", rep.failures.len() as f64);
    let other = rep.cases - rep.reached - rep.jammed - rep.failures.len();
    out.metric("other_stops", other as f64);
    out.note(format!(
        "{} packings of 20–120 particles (φ 0.45–0.62, monodisperse or Gaussian 0.3) in box, cylinder, \
         sphere and periodic containers at growth rates {:?}: {} reached their target, {} jammed first, \
         {other} stopped on another criterion (event or time budget), {} failed; largest overlap {:.2e} of \
         the smaller radius.",
        rep.cases,
        STRESS_GROWTH_RATES,
        rep.reached,
        rep.jammed,
        rep.failures.len(),
        rep.worst_overlap
    ));
    for f in rep.failures.iter().take(10) {
        out.note(format!("failed: {f:?}"));
    }
}
