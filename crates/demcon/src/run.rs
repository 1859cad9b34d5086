//! `demcon run SCENE.ron`: load a scene, run it, print a summary, write the outputs. A
//! transient whose scene sets `thermal.checkpoint` writes `OUT.checkpoint` beside the output
//! folder as it goes; `--resume` continues a killed run from it, and a completed run removes
//! it. SIGINT or SIGTERM stops a run without leaving half-written outputs (`signals.rs`).

use std::cell::Cell;
use std::ops::ControlFlow;
use std::path::PathBuf;
use std::process::ExitCode;
use std::sync::Arc;

use crate::progress::RunDisplay;
use anyhow::{Context, Result};
use clap::Args;
use demcon_core::StageObserver;
use demcon_scene::checkpoint::{checkpoint_path, remove_checkpoint};
use demcon_scene::output::check_output_dir;
use demcon_scene::{CheckpointOptions, RunOptions, Scene, run as run_scene, write_outputs};

/// Exit code of a run stopped by `--exit-after-checkpoints` (EX_TEMPFAIL: try again, with
/// `--resume`).
pub const EXIT_STOPPED: u8 = 75;

/// Arguments of `demcon run`.
#[derive(Debug, Args)]
pub struct RunArgs {
    /// The scene file (RON).
    pub scene: PathBuf,
    /// Output folder (default: `out/<scene name>`).
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Worker threads (default: all cores). Results depend on it only within round-off.
    #[arg(long)]
    pub threads: Option<usize>,
    /// No progress bar.
    #[arg(long)]
    pub quiet: bool,
    /// Continue the interrupted (killed) run whose checkpoint `OUT.checkpoint` lies beside the
    /// output folder; the results are those of an uninterrupted run. Needs the same scene and
    /// packing (only `thermal.checkpoint` may change).
    #[arg(long)]
    pub resume: bool,
    /// Test hook: exit at once with code 75 right after the N-th checkpoint is written, as a
    /// killed run would (no outputs, the checkpoint left).
    #[arg(long, hide = true, value_name = "N")]
    pub exit_after_checkpoints: Option<u64>,
    /// Run on MPI ranks with PETSc: `mpirun -n K demcon run SCENE.ron --distributed` (a demcon
    /// built with `--features petsc`; docs/distributed.md). With a `Tile` packing each rank
    /// builds and keeps only its block of the model and writes its piece of the outputs (rank 0
    /// `summary.json`, `particles.pvtu`); other scenes run whole on every rank with the linear
    /// solves distributed, rank 0 writing the outputs. Without mpirun it is one rank.
    /// Checkpoints are not written.
    #[arg(long)]
    pub distributed: bool,
}

/// Runs the subcommand.
pub fn run(args: RunArgs) -> Result<ExitCode> {
    let launch = crate::mpi::launch();
    // Until PETSc says otherwise, the launcher's rank 0 is the one that prints errors.
    crate::mpi::set_silent(launch.is_some_and(|l| l.rank != 0));
    // Declared first, dropped last: PetscFinalize after every distributed system is gone.
    let session = distributed_session(&args, launch)?;
    let result = run_in(args, launch, session.as_ref());
    if let (Some(_), Err(e)) = (&session, &result) {
        // Said before PetscFinalize: MPI_Finalize waits for every rank, so no other rank can
        // exit non-zero (which makes mpirun abort the job, rank 0 with it) before rank 0 has
        // printed why the run failed. `main` then prints nothing more.
        crate::report_error(e);
    }
    drop(session);
    result
}

/// The run itself, inside the PETSc session of a distributed run (`None`: serial).
fn run_in(
    args: RunArgs,
    launch: Option<crate::mpi::Launch>,
    session: Option<&demcon_scene::distributed::Session>,
) -> Result<ExitCode> {
    let rank0 = session.is_none_or(|s| s.rank() == 0);
    let threads = match (args.threads, session) {
        (None, Some(s)) if s.size() > 1 => Some(crate::mpi::threads_per_rank(
            launch.map_or(s.size(), |l| l.local_size),
        )),
        (t, _) => t,
    };
    crate::set_threads(threads)?;
    let mut scene =
        Scene::load(&args.scene).with_context(|| format!("loading scene {}", args.scene.display()))?;
    if session.is_some() {
        scene =
            scene.edit(|c| c.linear_solver.method = demcon_scene::config::LinearMethodConfig::Distributed)?;
    }
    let stem = args
        .scene
        .file_stem()
        .and_then(|s| s.to_str())
        .unwrap_or("scene")
        .to_string();
    let name = if scene.config().name.is_empty() {
        stem.clone()
    } else {
        scene.config().name.clone()
    };
    let out = args.out.unwrap_or_else(|| PathBuf::from("out").join(&stem));
    check_output_dir(&out).with_context(|| format!("output folder {}", out.display()))?;
    let checkpoint = checkpoint_path(&out).with_context(|| format!("output folder {}", out.display()))?;
    // From here on a SIGINT or SIGTERM removes the half-written outputs (keeping a
    // checkpoint) and exits with 130 or 143.
    crate::signals::clean_up_on_signals(
        crate::signals::RunFiles {
            out: out.clone(),
            checkpoint: checkpoint.clone(),
        },
        !rank0,
    )
    .context("installing the SIGINT/SIGTERM handlers")?;
    if !args.quiet && rank0 {
        announce_checkpoints(&scene, session.is_some(), &checkpoint);
    }
    if let Some(s) = session
        && demcon_scene::blocks::block_support(&scene).is_none()
    {
        // Each rank builds and keeps only its block of the model.
        let t0 = std::time::Instant::now();
        let outcome = demcon_scene::blocks::run_blocks(&scene, s, &out, &name)
            .with_context(|| format!("running scene {} by blocks", args.scene.display()))?;
        if rank0 {
            print_blocks(&name, &outcome.summary, t0.elapsed().as_secs_f64());
            println!("outputs in {}: {}", out.display(), outcome.files.join(", "));
        }
        return Ok(ExitCode::SUCCESS);
    }
    let written = Cell::new(0u64);
    let after_write = |_steps: u64, _t: f64| {
        written.set(written.get() + 1);
        if args.exit_after_checkpoints == Some(written.get()) {
            // As a kill: no unwinding, no outputs, the checkpoint left in place.
            std::process::exit(i32::from(EXIT_STOPPED));
        }
        ControlFlow::Continue(())
    };
    let display = RunDisplay::new(!args.quiet && rank0);
    let progress = |p: &demcon_packing::PackProgress| display.packing(p);
    let steps = display.clone();
    let transient_progress = Some(demcon_scene::ProgressFn::new(move |done, total| {
        steps.transient(done, total)
    }));
    let opts = RunOptions {
        progress: Some(&progress),
        transient_progress,
        stages: Some(Arc::new(display.clone())),
        // Checkpoints are one process's file: a distributed run writes none.
        checkpoint: session.is_none().then(|| CheckpointOptions {
            path: checkpoint.clone(),
            resume: args.resume,
            after_write: Some(&after_write),
        }),
    };
    let result = run_scene(&scene, &opts).with_context(|| format!("running scene {}", args.scene.display()));
    let result = match result {
        Ok(r) => r,
        Err(e) => {
            display.finish();
            return Err(e);
        }
    };
    if let Some(s) = session {
        // Collective: every rank reaches this point after the same run.
        let peak = result.stages.peak_rss_bytes().unwrap_or(0) as f64;
        s.gather_peak_memory(peak)
            .context("gathering the ranks' peak memory")?;
    }
    let mut result = result;
    if let (Some(_), Some(why)) = (
        session,
        matches!(
            scene.config().packing,
            demcon_scene::config::PackingConfig::Tile { .. }
        )
        .then(|| demcon_scene::blocks::block_support(&scene))
        .flatten(),
    ) {
        result.diagnostics.push(format!(
            "distributed: the model is replicated on every rank, not built by blocks ({why}): each rank holds \
             the whole model (about 1.4 kB per particle)"
        ));
    }
    if !rank0 {
        // Every rank computed the same result; rank 0 writes it.
        return Ok(ExitCode::SUCCESS);
    }
    display.started("outputs");
    let files = write_outputs(&name, &scene.config().outputs, &result, &out)
        .with_context(|| format!("writing outputs to {}", out.display()));
    display.finish();
    let files = files?;
    remove_checkpoint(&checkpoint).context("removing the checkpoint of the completed run")?;
    print_summary(&name, &result);
    if let Some(r) = &result.resumed {
        println!(
            "  resumed from {} at step {} (t = {} s)",
            checkpoint.display(),
            r.steps,
            r.t
        );
    }
    println!("outputs in {}: {}", out.display(), files.join(", "));
    Ok(ExitCode::SUCCESS)
}

/// Says where the scene's checkpoints go, or that a distributed run writes none.
fn announce_checkpoints(scene: &Scene, distributed: bool, checkpoint: &std::path::Path) {
    let Some(ck) = scene.config().thermal.as_ref().and_then(|t| t.checkpoint) else {
        return;
    };
    if distributed {
        eprintln!(
            "note: a distributed run writes no checkpoints (the scene's thermal.checkpoint is ignored)"
        );
        return;
    }
    let every = [
        ck.every_steps.map(|k| format!("{k} steps")),
        ck.every_seconds.map(|s| format!("{s} s")),
    ]
    .into_iter()
    .flatten()
    .collect::<Vec<_>>()
    .join(" or ");
    eprintln!("checkpoints every {every} in {}", checkpoint.display());
}

/// The PETSc session of `--distributed` after the launch checks (`crate::mpi`); `None` for
/// a serial run.
fn distributed_session(
    args: &RunArgs,
    launch: Option<crate::mpi::Launch>,
) -> Result<Option<demcon_scene::distributed::Session>> {
    if !args.distributed {
        if let Some(l) = launch.filter(|l| l.size > 1) {
            anyhow::bail!(
                "launched by mpirun as {} processes without --distributed: every process would run the \
                 whole scene alone and write the same outputs; add --distributed (a demcon built with \
                 --features petsc), or run without mpirun",
                l.size
            );
        }
        return Ok(None);
    }
    if args.resume {
        anyhow::bail!(
            "--resume cannot be combined with --distributed: a distributed run writes no checkpoints; \
             resume serially, or rerun with --distributed"
        );
    }
    let session = demcon_scene::distributed::Session::init().context("--distributed")?;
    crate::mpi::set_silent(session.rank() != 0);
    if let Some(l) = launch
        && l.size != session.size()
    {
        anyhow::bail!(
            "mpirun started {} processes but PETSc's MPI sees {} rank(s): this demcon is linked with \
             another MPI than the launcher's; launch it with the mpirun of the MPI PETSc was built \
             with (Debian: /usr/bin/mpirun from openmpi-bin)",
            l.size,
            session.size()
        );
    }
    Ok(Some(session))
}

/// The run's summary on the terminal: the model, what the physics gave, the cost.
fn print_summary(name: &str, r: &demcon_scene::RunResult) {
    let m = &r.model;
    match &m.report.tessellation {
        Some(t) => println!(
            "scene {name}: {} particles, φ = {:.4}, {} Laguerre facets (Z = {:.3}; {} dropped below {:.1e} m², \
             cell volumes {:+.1e} of the domain)",
            m.particles.len(),
            m.phi,
            m.graph.pairs.len(),
            m.graph.coordination(),
            t.dropped_facets,
            t.negligible_area_m2,
            t.volume_error
        ),
        None => println!(
            "scene {name}: {} particles, φ = {:.4}, {} contacts (Z = {:.3}, ε = {:.4})",
            m.particles.len(),
            m.phi,
            m.graph.pairs.len(),
            m.graph.coordination(),
            m.graph.report.epsilon
        ),
    }
    if let Some(h) = &r.homogenization {
        print_homogenization(h);
    }
    if let Some(p) = &m.report.packing {
        println!(
            "  packing: {:.2} s, {} events ({:.2e}/s), stop {:?}",
            p.wall_s, p.events, p.events_per_s, p.stop
        );
    }
    println!(
        "  {} {:.2} s, network {:.2} s",
        if m.report.tessellation.is_some() {
            "tessellation"
        } else {
            "contacts"
        },
        m.report.contacts_s,
        m.report.network_s
    );
    if let Some(peak) = r.stages.peak_rss_bytes() {
        println!(
            "  peak memory {:.2} GB ({:.0} bytes per particle)",
            peak as f64 / 1e9,
            peak as f64 / m.particles.len().max(1) as f64
        );
    }
    print_physics(r);
    print_distributed();
    println!("  total {:.2} s", r.wall_s);
}

/// The summary of a run by blocks (`summary.json`'s main figures).
fn print_blocks(name: &str, s: &serde_json::Value, wall_s: f64) {
    let per_rank = |k: &str| {
        s[k].as_array()
            .map(|a| a.iter().map(|v| v.to_string()).collect::<Vec<_>>().join(" / "))
            .unwrap_or_default()
    };
    println!(
        "scene {name}: {} particles by blocks on {} ranks (owned {}; ghosts {}; ghost width {:.3e} m)",
        s["n_particles"],
        s["ranks"],
        per_rank("owned_per_rank"),
        per_rank("ghosts_per_rank"),
        s["ghost_width_m"].as_f64().unwrap_or(0.0)
    );
    let solve = &s["solve"];
    if solve["scheme"] == "forward-euler" {
        println!(
            "  thermal forward-euler: {} steps of {:.3e} s to t = {} s (bound {:.3e} s), ghosts exchanged after each",
            solve["steps"],
            solve["dt_s"].as_f64().unwrap_or(f64::NAN),
            solve["t_end_s"].as_f64().unwrap_or(f64::NAN),
            solve["dt_bound_s"].as_f64().unwrap_or(f64::NAN)
        );
    } else {
        println!(
            "  {} steady: {} iterations, relative residual {:.2e}",
            if s["electric"].is_object() {
                "electric"
            } else {
                "thermal"
            },
            solve["iterations"],
            solve["relative_residual"].as_f64().unwrap_or(f64::NAN)
        );
    }
    let e = &s["electric"];
    if e.is_object() {
        println!(
            "  electric: R = {:.6e} Ω, I = {:.4e} A (in/out mismatch {:.1e}), Joule {:.4e} W",
            e["resistance_ohm"].as_f64().unwrap_or(f64::NAN),
            e["current_in"].as_f64().unwrap_or(f64::NAN),
            e["current_mismatch"].as_f64().unwrap_or(f64::NAN),
            e["joule_w"].as_f64().unwrap_or(f64::NAN)
        );
    }
    if let Some(probes) = s["probes"].as_array() {
        for p in probes {
            println!(
                "  probe {} {} at t = {} s: {:.6}",
                p["name"].as_str().unwrap_or("?"),
                p["field"].as_str().unwrap_or("?"),
                p["t"].as_f64().unwrap_or(0.0),
                p["value"].as_f64().unwrap_or(f64::NAN)
            );
        }
    }
    if let Some(l) = s["etc"]["lambda_e"].as_f64() {
        println!(
            "  ETC along {}: {l:.6} W/(m·K)",
            s["etc"]["axis"].as_str().unwrap_or("?")
        );
    }
    if let Some(p) = s["peak_rss_bytes_per_rank"].as_array() {
        let gb: Vec<String> = p
            .iter()
            .map(|v| format!("{:.3}", v.as_f64().unwrap_or(0.0) / 1e9))
            .collect();
        println!("  peak memory per rank: {} GB", gb.join(" / "));
    }
    println!("  total {wall_s:.2} s");
}

/// The effective tensors of a periodic homogenisation.
fn print_homogenization(h: &demcon_scene::Homogenization) {
    for (what, unit, t) in [
        ("effective conductivity tensor", "W/(m·K)", h.thermal.as_ref()),
        ("electric conductivity tensor", "S/m", h.electric.as_ref()),
    ] {
        let Some(t) = t else { continue };
        let x = &t.report;
        println!("  {what} ({unit}), periodic homogenisation, {:.2} s:", x.wall_s);
        for row in &x.tensor {
            println!("    [{:>12.6e} {:>12.6e} {:>12.6e}]", row[0], row[1], row[2]);
        }
        println!(
            "    along x, y, z: {:.6e} {:.6e} {:.6e}; eigenvalues {:.6e} {:.6e} {:.6e}; symmetry error {:.1e}",
            x.axes[0],
            x.axes[1],
            x.axes[2],
            x.eigenvalues[0],
            x.eigenvalues[1],
            x.eigenvalues[2],
            x.symmetry_error
        );
        if let Some(c) = &t.calibration {
            println!("    C_t = {:.5} calibrated by homogenisation", c.c_t);
        }
    }
}

/// The calibration, the thermal and electric solves, the ETC, the Halo, the probes and the
/// notes.
fn print_physics(r: &demcon_scene::RunResult) {
    if let Some(c) = r.thermal_setup.as_ref().and_then(|s| s.calibration.as_ref()) {
        println!(
            "  C_t = {:.4} (calibrated on this packing, {}, {} CG iterations)",
            c.c_t, c.method, c.iterations
        );
    }
    if let Some(t) = &r.thermal {
        let rep = &t.report;
        println!(
            "  thermal {}: {:.2} s, {} steps, {} CG iterations, dt = {:.3e} s (bound {:.3e} s{}), energy balance {:.1e}",
            rep.scheme,
            rep.wall_s,
            rep.steps,
            rep.iterations,
            rep.dt,
            rep.dt_bound,
            rep.dt_paper
                .map(|d| format!(", paper eq. 16: {d:.3e} s"))
                .unwrap_or_default(),
            rep.energy_balance_error
        );
    }
    if let Some(e) = &r.electric {
        let rep = &e.report;
        println!(
            "  electric: R = {} Ω, I = {:.4e} A (in/out mismatch {:.1e}), Joule {:.4e} W, {} {} iterations, {:.3} s",
            rep.resistance_ohm
                .map(|v| format!("{v:.6e}"))
                .unwrap_or_else(|| "-".into()),
            rep.current_in,
            rep.current_mismatch,
            rep.joule_w,
            rep.method,
            rep.iterations,
            rep.wall_s
        );
    }
    if let Some(etc) = &r.etc {
        println!(
            "  effective conductivity along {}: {:.5} W/(m·K)",
            etc.axis, etc.lambda_e
        );
    }
    if let Some((_, _, h)) = &r.halo {
        println!(
            "  Halo k = {} ({:?} phases): {:.1} members on average, {} truncated by the boundary, {:.2} s",
            h.ratio, h.phases, h.mean_members, h.n_truncated, h.wall_s
        );
    }
    for p in &r.probes {
        println!("  probe {} {} at t = {} s: {:.6}", p.name, p.field, p.t, p.value);
    }
    for d in &r.diagnostics {
        println!("  note: {d}");
    }
}

/// The distributed solve's totals, when there was one.
fn print_distributed() {
    let d = demcon_scene::distributed::stats();
    if d.ranks > 0 {
        println!(
            "  distributed ({}: {}, {} rank(s), {}–{} rows per rank, {} ghosts on rank 0): {} systems, {} KSP solves, {} iterations; \
             rank 0: assembly {:.2} s, set-up {:.2} s, solve {:.2} s, gather {:.2} s; peak memory per rank \
             {:.2}–{:.2} GB",
            demcon_scene::distributed::METHOD,
            d.solver,
            d.ranks,
            d.rows_per_rank.0,
            d.rows_per_rank.1,
            d.ghosts,
            d.systems,
            d.ksp_solves,
            d.iterations,
            d.assembly_s,
            d.setup_s,
            d.solve_s,
            d.gather_s,
            d.peak_rss_bytes.0 / 1e9,
            d.peak_rss_bytes.1 / 1e9
        );
    }
}
