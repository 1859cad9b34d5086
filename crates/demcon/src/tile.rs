//! `demcon tile IN --repeat NX,NY,NZ --out OUT`: a periodic packing file copied NX × NY × NZ
//! times into a larger periodic packing file (the scene's `packing: Tile(...)` as a file).

use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::{Context, bail};
use clap::Args;
use demcon_packing::{
    MemoryLimit, check_tile_memory, check_writable, format_xyzr, read_xyzr_file, summarize, tile,
    tiled_count, write_atomic_all,
};

/// Flags of `demcon tile`.
#[derive(Debug, Args)]
pub struct TileArgs {
    /// Periodic packing file (`x y z r` with a `# container periodic` line).
    file: PathBuf,
    /// Copies along x, y and z: NX,NY,NZ (each ≥ 1).
    #[arg(long, value_delimiter = ',')]
    repeat: Vec<usize>,
    /// Output packing file (written atomically).
    #[arg(long)]
    out: PathBuf,
}

/// Runs `demcon tile`.
pub fn run(a: TileArgs) -> anyhow::Result<ExitCode> {
    let [nx, ny, nz] = a.repeat[..] else {
        bail!(
            "invalid --repeat with {} values: give three counts NX,NY,NZ (each ≥ 1)",
            a.repeat.len()
        );
    };
    check_writable(&a.out).context("--out")?;
    let f = read_xyzr_file(&a.file).with_context(|| format!("reading packing {}", a.file.display()))?;
    let Some(container) = f.container else {
        bail!(
            "{} has no `# container` line: only a periodic packing can be tiled (add `# container periodic LX LY LZ`)",
            a.file.display()
        );
    };
    // The count and its memory first: a tiling too large for this machine is refused with the
    // estimate instead of being killed by the system half-way.
    let total = tiled_count(f.particles.len(), [nx, ny, nz], "repeat").context("--repeat")?;
    check_tile_memory(total, &MemoryLimit::current(), "repeat").context("--repeat")?;
    let (tiled, big) = tile(&f.particles, &container, [nx, ny, nz]).context("--repeat")?;
    let mut notes = f.notes.clone();
    notes.push(format!(
        "tiled {nx} x {ny} x {nz} from {} ({} particles)",
        a.file.display(),
        f.particles.len()
    ));
    let text = format_xyzr(&tiled, &big, &notes);
    write_atomic_all(&[(a.out.as_path(), text.as_bytes())]).context("writing the tiled packing")?;
    println!("{}", summarize(&tiled, &big, 2.0));
    println!("written            {}", a.out.display());
    Ok(ExitCode::SUCCESS)
}
