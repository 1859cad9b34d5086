//! `cargo xtask`: project automation in Rust (no loose shell scripts).

fn main() -> anyhow::Result<()> {
    Ok(())
}
