//! The full packer stress sweep: `cargo run --release -p demcon-packing --example
//! stress_packings [-- CASES]` (default 1000 small packings, ~15 s); exits with status 1 on
//! any failure.

fn main() -> std::process::ExitCode {
    let cases = std::env::args()
        .nth(1)
        .map(|s| s.parse().expect("CASES must be a whole number"))
        .unwrap_or(1000);
    let r = demcon_packing::stress_packings(cases);
    println!(
        "{} cases: {} reached the target, {} jammed, worst overlap {:e} of the smaller radius, {} failure(s)",
        r.cases,
        r.reached,
        r.jammed,
        r.worst_overlap,
        r.failures.len()
    );
    for f in &r.failures {
        println!("{f:?}");
    }
    if r.failures.is_empty() {
        std::process::ExitCode::SUCCESS
    } else {
        std::process::ExitCode::FAILURE
    }
}
