//! The discretization against direct quadrature and finite differences.

use super::*;
use ssm_api::{Harmonic, PolyVector, SparseMatrix};
use ssm_kernel::continuation::Problem;
use ssm_plugin_kit::MechanicalSystem;

/// `x'' + 0.04 x' + x + 0.5 x^2 + 0.3 x^3 = eps (cos Omega t + 0.4 sin 2 Omega t)`.
fn duffing() -> System {
    let mut m = MechanicalSystem::new("duffing", &["x"]);
    m.mass = SparseMatrix::diagonal(&[1.0]);
    m.damping = SparseMatrix::diagonal(&[0.04]);
    m.stiffness = SparseMatrix::diagonal(&[1.0]);
    let mut f = PolyVector::zeros(1, 2);
    f.push(0, 0.5, &[(0, 2)]);
    f.push(0, 0.3, &[(0, 3)]);
    m.internal_force = f;
    let mut c1 = PolyVector::zeros(1, 2);
    c1.push(0, 1.0, &[]);
    let mut s2 = PolyVector::zeros(1, 2);
    s2.push(0, 0.4, &[]);
    m.forcing = vec![
        Harmonic {
            multiple: 1.0,
            cos: c1,
            sin: PolyVector::zeros(1, 2),
        },
        Harmonic {
            multiple: 2.0,
            cos: PolyVector::zeros(1, 2),
            sin: s2,
        },
    ];
    System::from_model("test", m.into_model().expect("model")).expect("system")
}

/// Reference: `<phi_p, J phi_q> / <phi_p, phi_p>` by a 4000-point rectangle
/// rule (exact for trigonometric polynomials of degree < 4000), to 1e-12.
#[test]
fn galerkin_block_equals_quadrature() {
    let h = 3;
    let kk = 2 * h + 1;
    let cs: Vec<f64> = (0..=4 * h)
        .map(|i| 0.3 / (1.0 + i as f64) - 0.05 * i as f64)
        .collect();
    let j = |psi: f64| -> f64 {
        (1..=2 * h).fold(cs[0], |v, k| {
            v + cs[2 * k - 1] * (k as f64 * psi).cos() + cs[2 * k] * (k as f64 * psi).sin()
        })
    };
    let phi = |q: usize, psi: f64| -> f64 {
        if q == 0 {
            1.0
        } else if q % 2 == 1 {
            (q.div_ceil(2) as f64 * psi).cos()
        } else {
            ((q / 2) as f64 * psi).sin()
        }
    };
    let mut block = vec![0.0; kk * kk];
    galerkin_block(&cs, h, &mut block);
    let m = 4000;
    for p in 0..kk {
        for q in 0..kk {
            let mut s = 0.0;
            for i in 0..m {
                let psi = 2.0 * std::f64::consts::PI * i as f64 / m as f64;
                s += phi(p, psi) * j(psi) * phi(q, psi);
            }
            s /= m as f64;
            let norm = if p == 0 { 1.0 } else { 0.5 };
            let want = s / norm;
            assert!(
                (block[p * kk + q] - want).abs() < 1e-12,
                "G[{p}][{q}] = {} against {want}",
                block[p * kk + q]
            );
        }
    }
}

/// Reference: central differences of the residual (step 1e-6, agreement
/// 1e-6 relative to the largest entry), every column of the Jacobian
/// including the frequency column.
#[test]
fn jacobian_equals_finite_differences() {
    let sys = duffing();
    let mut hb = HarmonicBalance::new(&sys, 0.1, 4, 1).expect("setup");
    hb.amplitude_scale = 0.7;
    hb.frequency_scale = 0.5;
    let nu = hb.n_coefficients();
    let u: Vec<f64> = (0..=nu)
        .map(|i| {
            if i == nu {
                2.1
            } else {
                0.3 * ((i as f64) * 1.7).sin()
            }
        })
        .collect();
    let (c, omega) = hb.unscale(&u);
    let vals = hb.jacobian_values(&c, omega);
    let dense = SparseColMat::new(hb.solver.pattern().clone(), vals).to_dense();
    let big = (0..nu)
        .flat_map(|i| (0..=nu).map(move |j| (i, j)))
        .map(|(i, j)| dense[(i, j)].abs())
        .fold(0.0, f64::max);
    for col in 0..=nu {
        let (mut up, mut um) = (u.clone(), u.clone());
        up[col] += 1e-6;
        um[col] -= 1e-6;
        let rp = hb.residual(&up).expect("finite");
        let rm = hb.residual(&um).expect("finite");
        for r in 0..nu {
            let fd = (rp[r] - rm[r]) / 2e-6;
            assert!(
                (dense[(r, col)] - fd).abs() < 1e-6 * big,
                "J[{r}][{col}] = {} against {fd}",
                dense[(r, col)]
            );
        }
    }
}

/// Forcing harmonics that are not periodic at the period multiple are a
/// typed error; `1.5 Omega` is periodic at twice the period.
#[test]
fn non_periodic_forcing_is_refused() {
    let mut sys = duffing();
    sys.forcing[1].multiple = 1.5;
    let e = HarmonicBalance::new(&sys, 0.1, 4, 1)
        .err()
        .expect("1.5 Omega at m = 1");
    assert!(
        matches!(
            e,
            HarmonicBalanceError::NonIntegerHarmonic {
                period_multiple: 1,
                ..
            }
        ),
        "{e}"
    );
    assert!(HarmonicBalance::new(&sys, 0.1, 4, 2).is_ok());
    assert!(
        HarmonicBalance::new(&sys, 0.0, 4, 1).is_ok(),
        "no forcing, no check"
    );
}
