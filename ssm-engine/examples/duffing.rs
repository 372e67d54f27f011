//! The engine as a library, without a scene: the forced Duffing oscillator
//! `x'' + 2 zeta x' + x + kappa x^3 = eps cos(Omega t)` built from its
//! matrices in code, its spectrum and SSM, the backbone and the damping curve
//! with their error estimates, the forced response of the reduced model and
//! the full system's periodic orbits (harmonic balance with Floquet
//! multipliers) over the same band, printed side by side.
//!
//! Run: `cargo run --release --example duffing` (the suite's
//! `examples::duffing_example_runs_and_agrees_with_the_full_system` runs it).
//! It fails (exit code 1) if the reduced peak amplitude and the full
//! system's differ by more than three times the reduced curve's error
//! estimate.

use ssm_api::{Harmonic, PolyVector, SparseMatrix};
use ssm_core::spectrum::Normalization;
use ssm_core::{
    backbone, compute_ssm, forced_response, reference_frc, spectral, BackboneSpec, FrcSpec,
    ReferenceSettings, SpectrumSpec, SsmOptions, SsmSpec, System,
};
use ssm_engine::analyses::damping::{damping_curves, DampingSpec};
use ssm_engine::analyses::Context;
use ssm_plugin_kit::MechanicalSystem;

/// Damping ratio, cubic stiffness, forcing amplitude.
const ZETA: f64 = 0.01;
const KAPPA: f64 = 0.5;
const EPS: f64 = 0.01;

/// The Duffing oscillator from its mass, damping and stiffness matrices, its
/// cubic force `kappa x^3` and the load `cos(Omega t)` (scaled by `eps`).
fn duffing() -> Result<System, Box<dyn std::error::Error>> {
    let mut m = MechanicalSystem::new("duffing", &["x"]);
    m.mass = SparseMatrix::diagonal(&[1.0]);
    m.damping = SparseMatrix::diagonal(&[2.0 * ZETA]);
    m.stiffness = SparseMatrix::diagonal(&[1.0]);
    let mut f = PolyVector::zeros(1, 2);
    f.push(0, KAPPA, &[(0, 3)]);
    m.internal_force = f;
    let mut load = PolyVector::zeros(1, 2);
    load.push(0, 1.0, &[]);
    m.forcing = vec![Harmonic {
        multiple: 1.0,
        cos: load,
        sin: PolyVector::zeros(1, 2),
    }];
    Ok(System::from_model("example", m.into_model()?)?)
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let sys = duffing()?;
    let x = sys.output("x").ok_or("the model names its output x")?;
    let tolerance = 0.01;

    // spectrum, master pair and non-resonance checks, then the SSM to O(7)
    let ssm_spec = SsmSpec {
        master_pairs: vec![1],
        order: Some(7),
        normalization: Normalization::Unit,
        ..SsmSpec::default()
    };
    let sp = spectral(&ssm_spec, &SpectrumSpec::default(), &sys, 7)?;
    for w in &sp.warnings {
        println!("warning: {w}");
    }
    let masters = sp.masters;
    let others = ssm_core::ssm::non_master(&sp.spectrum.eigenvalues, &masters);
    let expansion = compute_ssm(
        &sys,
        &masters,
        &others,
        &SsmOptions {
            order: 7,
            resonance_tol: ssm_spec.resonance_tol,
        },
    )?;
    println!(
        "master eigenvalue {:.6}, SSM to O({})",
        masters[0].lambda, expansion.order
    );

    // backbone and damping curve with their estimates
    let spec = BackboneSpec {
        points: 6,
        ..BackboneSpec::up_to(0.3)
    };
    let curves = backbone(&expansion, &sys, &masters[0], &spec, &[x], tolerance)?;
    let outputs = [x];
    let cx = Context::new(&sys, &masters, &expansion, &outputs, tolerance);
    let damping = damping_curves(
        &DampingSpec {
            points: 6,
            ..DampingSpec::up_to(0.3)
        },
        &cx,
    )?;
    println!("\n   amplitude x    omega      zeta(x)    estimate");
    for (b, d) in curves[0].points.iter().zip(&damping.curves[0].points) {
        println!(
            "   {:10.5}  {:10.6}  {:10.6}  {}",
            b.amplitudes[0],
            b.omega,
            d.output_zeta[0],
            d.error_estimate
                .map_or("exact".into(), |e| format!("{:.1e}", e))
        );
    }

    // the reduced model's forced response near the resonance
    let band = [0.9, 1.2];
    let frc = forced_response(
        &expansion,
        &sys,
        &masters,
        &FrcSpec::new(vec![EPS], band),
        &[x],
        tolerance,
    )?;
    let curve = frc.curves.first().ok_or("one forced response curve")?;
    let peak = frc
        .rows
        .iter()
        .max_by(|a, b| a.linf[0].total_cmp(&b.linf[0]))
        .ok_or("a forced response")?;
    println!(
        "\nreduced FRC (O({}), eps = {EPS}): peak |x| = {:.6} at Omega = {:.5}, estimated error {:.1e}",
        curve.order,
        peak.linf[0],
        peak.omega,
        curve.error_estimate()
    );
    for b in &curve.bifurcations {
        println!("   {} at Omega = {:.5}", b.kind, b.omega);
    }

    // the full system's periodic orbits over the same band
    let settings = ReferenceSettings {
        epsilon: EPS,
        omega_range: (band[0], band[1]),
        harmonics: 7,
        step: 0.05,
        tol: 1e-10,
        max_steps: 2000,
        outputs: vec![x.clone()],
        period_doubling: false,
        stability: true,
        points_at: Vec::new(),
        seeds: Vec::new(),
    };
    let full = reference_frc(&sys, &settings, |_| true)?;
    let full_peak = full
        .orbits
        .iter()
        .max_by(|a, b| a.linf[0].total_cmp(&b.linf[0]))
        .ok_or("a full-system orbit")?;
    println!(
        "full system (harmonic balance, 7 harmonics): peak |x| = {:.6} at Omega = {:.5}, {} orbits",
        full_peak.linf[0],
        full_peak.omega,
        full.orbits.len()
    );
    for e in &full.events {
        println!("   {:?} at Omega = {:.5}", e.kind, e.orbit.omega);
    }

    let difference = (peak.linf[0] / full_peak.linf[0] - 1.0).abs();
    println!(
        "\npeak amplitude: reduced against full {difference:.1e} (estimate {:.1e})",
        curve.error_estimate()
    );
    if difference > curve.error_estimate().max(1e-4) * 3.0 {
        return Err(format!(
            "the reduced peak differs from the full system's by {difference:.1e}, beyond its estimate"
        )
        .into());
    }
    Ok(())
}
