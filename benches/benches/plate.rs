//! The von Karman plate of the `von-karman-plate` plugin (simply supported,
//! 1 m x 1 m x 10 mm aluminium, `nx = ny = PLATE_BENCH_N` elements, 32 by
//! default: 12,036 states; 90 gives 96,484): the O(5) SSM of the first pair
//! and its one-pair forced response over 280..380 rad/s (`eps = 1`, the
//! non-autonomous order the engine chooses), timed apart, so that issue 43's
//! target, a forced response that costs less than its SSM, reads off one
//! report. Each case first prints what it computes (states, the response's
//! points, peak and error estimate, the linear algebra of each stage).
//!
//! Run with `cargo build --release --workspace && cargo bench -p ssm-benches
//! --bench plate` (`PLATE_BENCH_N=90` for the 10^5-state plate: about 30 s an
//! iteration).

use std::hint::black_box;

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};
use ssm_core::rom::forced_response::forced_response;
use ssm_core::spec::FrcSpec;
use ssm_core::spectrum::{self, Method, Normalization, SpectrumOptions};
use ssm_core::ssm::{self, SsmOptions};
use ssm_tests::system;

fn plate(c: &mut Criterion) {
    // as the engine runs: freed factors reused, not faulted in afresh
    ssm_kernel::heap::retain_freed_memory();
    let n: usize = std::env::var("PLATE_BENCH_N")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(32);
    let sys = system("von-karman-plate", "plate", &format!("nx = {n}\nny = {n}"));
    let sp = spectrum::compute(
        sys.a.as_ref(),
        sys.b.as_ref(),
        &SpectrumOptions {
            method: Some(Method::Sparse),
            modes: 6,
            shift: 0.0,
            normalization: Normalization::Unit,
            velocities: sys.velocities(),
        },
    )
    .expect("plate spectrum");
    let masters =
        spectrum::master_modes(&sys, &sp, &[1], Normalization::Unit).expect("master pair");
    let others = ssm::non_master(&sp.eigenvalues, &masters);
    let options = SsmOptions {
        order: 5,
        resonance_tol: 0.05,
    };
    let expansion = || ssm::compute(&sys, &masters, &others, &options).expect("SSM");
    let ssm = expansion();
    let spec = FrcSpec {
        epsilon: vec![1.0],
        omega_range: [280.0, 380.0],
        orders: Some(vec![5]),
        resonance: None,
        points: FrcSpec::DEFAULT_POINTS,
        rho_max: None,
        nonautonomous_order: None,
    };
    let output = sys.output("w_center").expect("output");
    let response = || forced_response(&ssm, &sys, &masters, &spec, &[output], 0.01).expect("FRC");
    let frc = response();
    let curve = &frc.curves[0];
    println!(
        "plate {n} x {n}: {} states; SSM {:?}; forced response: {} points, {:?}, linear algebra {:?}",
        sys.n_states(),
        ssm.timing.linear.counts(),
        curve.points,
        curve.details,
        frc.linear
    );
    let name = format!("{n} x {n} ({} states)", sys.n_states());
    let mut g = c.benchmark_group("plate");
    g.sample_size(10);
    g.bench_function(BenchmarkId::new("O(5) SSM", &name), |b| {
        b.iter(|| black_box(expansion()))
    });
    g.bench_function(BenchmarkId::new("forced response", &name), |b| {
        b.iter(|| black_box(response()))
    });
    g.finish();
}

criterion_group!(benches, plate);
criterion_main!(benches);
