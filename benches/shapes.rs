//! Random sequential addition of shaped inclusions ([`demcon_packing::place_shapes`]).
//!
//! - `rsa_fibres/aspect10_f0.2/10000`: the issue-34 case, 10⁴ round-ended fibres of aspect 10
//!   (length / diameter), isotropic, to f = 0.2 in a periodic box (target ≤ 10 s).
//! - `rsa_spheroids/aspect5_f0.2/10000`: 10⁴ prolate spheroids of aspect 5, isotropic, f = 0.2.
//!
//! Each case prints the fraction reached, tries, rattles and the smallest gap once.
//! `cargo bench -p demcon-benches --bench shapes`.

use criterion::{Criterion, criterion_group};
use demcon_core::Container;
use demcon_packing::{ShapeKind, ShapeParams, place_shapes};

/// A periodic cube holding `n` shapes of `kind`, aspect `aspect` and radius 1 at `fraction`.
fn params(kind: ShapeKind, aspect: f64, n: usize, fraction: f64) -> ShapeParams {
    let one = ShapeParams::new(
        Container::Periodic { size: [1.0; 3] },
        kind,
        aspect,
        1.0,
        fraction,
    );
    let v = match kind {
        ShapeKind::Spheroid => 4.0 / 3.0 * std::f64::consts::PI * aspect,
        ShapeKind::Cylinder { round: true } => {
            std::f64::consts::PI * (2.0 * aspect - 2.0) + 4.0 / 3.0 * std::f64::consts::PI
        }
        ShapeKind::Cylinder { round: false } => std::f64::consts::PI * 2.0 * aspect,
    };
    let edge = (n as f64 * v / fraction).cbrt();
    ShapeParams {
        container: Container::Periodic { size: [edge; 3] },
        ..one
    }
}

fn rsa(c: &mut Criterion) {
    let mut g = c.benchmark_group("rsa");
    g.sample_size(10);
    let cases = [
        (
            "fibres/aspect10_f0.2",
            params(ShapeKind::Cylinder { round: true }, 10.0, 10_000, 0.2),
        ),
        (
            "spheroids/aspect5_f0.2",
            params(ShapeKind::Spheroid, 5.0, 10_000, 0.2),
        ),
    ];
    for (name, p) in cases {
        // Deterministic: every iteration places the same shapes, so the report is printed once.
        let reported = std::cell::Cell::new(false);
        g.bench_function(format!("{name}/10000"), |b| {
            b.iter(|| {
                let (shapes, r) = place_shapes(&p, 1).expect("placement");
                if !reported.replace(true) {
                    eprintln!(
                        "\n{name}: {} shapes, f = {:.4}, {} tries, {} rattles, min gap {:.3e}, {:.2} s",
                        r.count, r.fraction, r.attempts, r.relaxations, r.min_distance, r.wall_s
                    );
                }
                shapes
            })
        });
    }
    g.finish();
}

criterion_group!(benches, rsa);

fn main() {
    benches();
    criterion::Criterion::default()
        .configure_from_args()
        .final_summary();
}
