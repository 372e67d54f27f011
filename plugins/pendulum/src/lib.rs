//! Plugin `pendulum`: the pendulum family of Li, Jain & Haller (2023), Sect. 5.2,
//! written in the coordinates of the papers with `sin`/`cos` as expressions; the
//! engine recasts them (auxiliaries `u = sin phi`, `1 - cos phi`) and shifts the
//! hanging equilibrium to the origin.
//!
//! - `simple`: `phi'' + c phi' + sin(phi) = eps f cos(Omega t)`, eq. (21).
//! - `slider`: a pendulum of length `l` hinged to a slider on a spring, eqs.
//!   (32)-(33), with gravity along `+y`; the equilibrium (34) is given to the
//!   engine.
//! - `chain`: `n - 1` pendulums hanging below the slider, coupled by rotational
//!   springs and dampers, Appendix F, eqs. (97)-(106), equilibrium (107).
//!
//! All three are built with the mechanical builder: mass, damping and stiffness
//! matrices, gravity as constant force expressions, configuration constraints as
//! expressions; multipliers and constraint forces `G(x)^T mu` come from the
//! builder. Outputs carry the papers' symbols (`phi`; `x1`, `y1`, `x2`, `y2`,
//! `phi2`, `mu1`..; `x_i`, `y_i`, `phi_i`, `mu_j` and `phi_n`); positions are
//! deviations from the equilibrium.
//!
//! ## The chain's rotational damping
//! The paper prints `c = 0.02` next to the eigenvalues of eq. (45). With
//! `c = 0.02` the first two pairs are `-0.0566 +- 1.994i` and `-0.0649 +- 4.9038i`,
//! so the real parts miss the printed `-0.0569` and `-0.0730`; with `c = 0.06`
//! they are `-0.0569 +- 1.9939i` and `-0.0730 +- 4.9038i`, both to the printed
//! digits. The published computation behind eq. (45) therefore used `c = 0.06`,
//! which is the default here (the test `chain_spectrum_matches_eq45` checks both
//! findings).
//!
//! # References
//! M. Li, S. Jain, G. Haller, *Model reduction for constrained mechanical systems
//! via spectral submanifolds*, Nonlinear Dyn. 111 (2023), Sect. 5.2 and Appendix F.

use ssm_api::{
    ErrorKind, Harmonic, Model, ModelInfo, MotionKind, PluginError, PolyVector, SparseMatrix,
};
use ssm_plugin_kit::{Constraints, Equilibrium, Expr, MechanicalSystem, ParamSpec, Params};

fn simple_specs() -> Vec<ParamSpec> {
    vec![
        ParamSpec::float("c", 0.001, "damping coefficient (eq. 21)"),
        ParamSpec::float(
            "f",
            1.0,
            "forcing amplitude, eps*f*cos(Omega t) on phi (eq. 21)",
        ),
    ]
}

fn slider_specs() -> Vec<ParamSpec> {
    vec![
        ParamSpec::float("m1", 1.0, "slider mass (eq. 32)"),
        ParamSpec::float("m2", 1.0, "pendulum mass (eq. 32)"),
        ParamSpec::float("c1", 0.02, "slider damping (eq. 32)"),
        ParamSpec::float("c2", 0.02, "rotational damping of the pendulum (eq. 32)"),
        ParamSpec::float("k1", 7.48, "slider spring (eq. 32)"),
        ParamSpec::float("k2", 1.0, "rotational spring of the pendulum (eq. 32)"),
        ParamSpec::float("g", 9.8, "gravity (eq. 32)"),
        ParamSpec::float(
            "l",
            1.0,
            "pendulum length (value of the published computation)",
        ),
        ParamSpec::float(
            "J2",
            1.0 / 12.0,
            "pendulum moment of inertia (value of the published computation)",
        ),
        ParamSpec::float(
            "f1",
            1.0,
            "forcing amplitude on the slider, eps*f1*cos(Omega t) (eq. 35)",
        ),
    ]
}

fn chain_specs() -> Vec<ParamSpec> {
    vec![
        ParamSpec::count("n", 41, "number of bodies: the slider and n - 1 pendulums (Appendix F)"),
        ParamSpec::float("m1", 0.61, "slider mass"),
        ParamSpec::float("m", 0.02, "mass of each pendulum, m_2 = ... = m_n"),
        ParamSpec::float("c1", 0.22, "slider damping"),
        ParamSpec::float(
            "c",
            0.06,
            "rotational damping between neighbours (0.06 reproduces eq. (45); the paper prints 0.02)",
        ),
        ParamSpec::float("k1", 6.5, "slider spring"),
        ParamSpec::float("k", 4.1, "rotational spring between neighbours"),
        ParamSpec::float("l", 0.03, "pendulum length; J_i = m_i l^2 / 12"),
        ParamSpec::float("g", 9.8, "gravity"),
        ParamSpec::float("f1", 1.0, "forcing amplitude on the slider, eps*f1*cos(Omega t) (eq. 109)"),
    ]
}

fn models() -> Vec<ModelInfo> {
    let info = |name: &str, description: &str, specs: Vec<ParamSpec>| ModelInfo {
        name: name.into(),
        description: description.into(),
        params: specs.iter().map(ParamSpec::info).collect(),
    };
    vec![
        info(
            "simple",
            "damped pendulum phi'' + c phi' + sin(phi) = eps f cos(Omega t), eq. (21)",
            simple_specs(),
        ),
        info(
            "slider",
            "pendulum on a sprung slider with 1:3 internal resonance, eqs. (32)-(36)",
            slider_specs(),
        ),
        info(
            "chain",
            "chain of n - 1 pendulums hanging from a sprung slider, Appendix F, eqs. (97)-(115)",
            chain_specs(),
        ),
    ]
}

fn positive(p: &Params, names: &[&str]) -> Result<(), PluginError> {
    for &name in names {
        let v = p.float(name);
        if !(v.is_finite() && v > 0.0) {
            return Err(PluginError::new(
                ErrorKind::InvalidParameter,
                name,
                &format!("must be positive, got {v}"),
            ));
        }
    }
    Ok(())
}

fn non_negative(p: &Params, names: &[&str]) -> Result<(), PluginError> {
    for &name in names {
        let v = p.float(name);
        if !(v.is_finite() && v >= 0.0) {
            return Err(PluginError::new(
                ErrorKind::InvalidParameter,
                name,
                &format!("must be non-negative, got {v}"),
            ));
        }
    }
    Ok(())
}

/// A constant forcing amplitude `amp` on dof `dof` of `n`.
fn harmonic_on(n: usize, dof: usize, amp: f64) -> Vec<Harmonic> {
    let mut cos = PolyVector::zeros(n, 2 * n);
    cos.push(dof, amp, &[]);
    vec![Harmonic {
        multiple: 1.0,
        cos,
        sin: PolyVector::zeros(n, 2 * n),
    }]
}

fn simple(p: &Params) -> Result<Model, PluginError> {
    non_negative(p, &["c"])?;
    let mut s = MechanicalSystem::new("simple", &["phi"]);
    s.dof_motion = vec![MotionKind::Rotational];
    s.mass = SparseMatrix::diagonal(&[1.0]);
    s.damping = SparseMatrix::diagonal(&[p.float("c")]);
    s.force_expressions = vec![(0, Expr::var(0).sin())];
    s.forcing = harmonic_on(1, 0, p.float("f"));
    Ok(s.into_model()?)
}

fn slider(p: &Params) -> Result<Model, PluginError> {
    positive(p, &["m1", "m2", "l", "J2"])?;
    non_negative(p, &["c1", "c2", "k1", "k2", "g"])?;
    let (m1, m2, l, g) = (p.float("m1"), p.float("m2"), p.float("l"), p.float("g"));
    let mut s = MechanicalSystem::new("slider", &["x1", "y1", "x2", "y2", "phi2"]);
    s.dof_motion = vec![
        MotionKind::Translational,
        MotionKind::Translational,
        MotionKind::Translational,
        MotionKind::Translational,
        MotionKind::Rotational,
    ];
    s.mass = SparseMatrix::diagonal(&[m1, m1, m2, m2, p.float("J2")]);
    s.damping = SparseMatrix::diagonal(&[p.float("c1"), 0.0, 0.0, 0.0, p.float("c2")]);
    s.stiffness = SparseMatrix::diagonal(&[p.float("k1"), 0.0, 0.0, 0.0, p.float("k2")]);
    // gravity along +y: the potential -m g y gives the force term -m g
    s.force_expressions = vec![(1, Expr::constant(-m1 * g)), (3, Expr::constant(-m2 * g))];
    let x = Expr::var;
    let phi = x(4);
    // eq. (33)
    s.constraints = Some(Constraints::expressions(
        5,
        vec![
            x(1),
            x(2) - (x(0) + 0.5 * l * phi.clone().sin()),
            x(3) - (x(1) + 0.5 * l * phi.cos()),
        ],
    ));
    // eq. (34): y2 = 0.5 l, mu1 = (m1 + m2) g, mu3 = m2 g
    s.equilibrium = Some(Equilibrium {
        x: vec![0.0, 0.0, 0.0, 0.5 * l, 0.0],
        mu: vec![(m1 + m2) * g, 0.0, m2 * g],
    });
    s.forcing = harmonic_on(5, 0, p.float("f1"));
    Ok(s.into_model()?)
}

/// Indices of `x_i`, `y_i` (and `phi_i` for `i >= 2`) of body `i` (1-based).
fn body(i: usize) -> (usize, usize, usize) {
    if i == 1 {
        (0, 1, usize::MAX)
    } else {
        let b = 2 + 3 * (i - 2);
        (b, b + 1, b + 2)
    }
}

fn chain(p: &Params) -> Result<Model, PluginError> {
    let n = p.count("n") as usize;
    if !(2..=100_000).contains(&n) {
        return Err(PluginError::new(
            ErrorKind::InvalidParameter,
            "n",
            &format!("the chain needs 2 <= n <= 100000 bodies, got {n}"),
        ));
    }
    positive(p, &["m1", "m", "l"])?;
    non_negative(p, &["c1", "c", "k1", "k", "g"])?;
    let (m1, m, l, g) = (p.float("m1"), p.float("m"), p.float("l"), p.float("g"));
    let (c, k) = (p.float("c"), p.float("k"));
    let j = m * l * l / 12.0;
    let mut names: Vec<String> = vec!["x1".into(), "y1".into()];
    for i in 2..=n {
        names.extend([format!("x{i}"), format!("y{i}"), format!("phi{i}")]);
    }
    let refs: Vec<&str> = names.iter().map(String::as_str).collect();
    let nd = refs.len();
    let mut s = MechanicalSystem::new("chain", &refs);
    s.dof_motion = (0..nd)
        .map(|d| {
            if d >= 2 && (d - 2) % 3 == 2 {
                MotionKind::Rotational
            } else {
                MotionKind::Translational
            }
        })
        .collect();
    let mut mass = vec![m1, m1];
    for _ in 2..=n {
        mass.extend([m, m, j]);
    }
    s.mass = SparseMatrix::diagonal(&mass);
    // slider spring and damper; rotational springs/dampers to the ground (phi2)
    // and between neighbours, eqs. (99), (104)-(106)
    let mut kk = SparseMatrix::zeros(nd, nd);
    let mut cc = SparseMatrix::zeros(nd, nd);
    kk.push(0, 0, p.float("k1"));
    cc.push(0, 0, p.float("c1"));
    kk.push(body(2).2, body(2).2, k);
    cc.push(body(2).2, body(2).2, c);
    for i in 3..=n {
        let (a, b) = (body(i - 1).2, body(i).2);
        for (mat, v) in [(&mut kk, k), (&mut cc, c)] {
            mat.push(a, a, v);
            mat.push(b, b, v);
            mat.push(a, b, -v);
            mat.push(b, a, -v);
        }
    }
    s.stiffness = kk;
    s.damping = cc;
    s.force_expressions = (1..=n)
        .map(|i| (body(i).1, Expr::constant(-mass[body(i).1] * g)))
        .collect();
    // eqs. (100)-(101): rod i has its ends at (x_i -+ l/2 sin phi_i, y_i -+ l/2 cos phi_i)
    let x = Expr::var;
    let sin: Vec<Expr> = (0..=n)
        .map(|i| {
            if i >= 2 {
                x(body(i).2).sin()
            } else {
                Expr::constant(0.0)
            }
        })
        .collect();
    let cos: Vec<Expr> = (0..=n)
        .map(|i| {
            if i >= 2 {
                x(body(i).2).cos()
            } else {
                Expr::constant(0.0)
            }
        })
        .collect();
    let h = 0.5 * l;
    let mut g_c = vec![
        x(1),
        x(body(2).0) - h * sin[2].clone() - x(0),
        x(body(2).1) - h * cos[2].clone() - x(1),
    ];
    for i in 2..n {
        let (xi, yi, _) = body(i);
        let (xj, yj, _) = body(i + 1);
        g_c.push(x(xj) - h * sin[i + 1].clone() - (x(xi) + h * sin[i].clone()));
        g_c.push(x(yj) - h * cos[i + 1].clone() - (x(yi) + h * cos[i].clone()));
    }
    s.constraints = Some(Constraints::expressions(nd, g_c));
    // eq. (107): y_i = l/2 + (i - 2) l, mu_{2i-1} = sum_{j >= i} m_j g
    let mut x_eq = vec![0.0; nd];
    for i in 2..=n {
        x_eq[body(i).1] = h + (i - 2) as f64 * l;
    }
    let mut mu_eq = vec![0.0; 2 * n - 1];
    let mut below = 0.0;
    for i in (1..=n).rev() {
        below += mass[body(i).1] * g;
        mu_eq[2 * i - 2] = below;
    }
    s.equilibrium = Some(Equilibrium { x: x_eq, mu: mu_eq });
    s.extra_outputs = vec![("phi_n".into(), vec![(body(n).2, 1.0)])];
    s.forcing = harmonic_on(nd, 0, p.float("f1"));
    Ok(s.into_model()?)
}

fn build(name: &str, params: &str) -> Result<Model, PluginError> {
    match name {
        "simple" => simple(&Params::parse(params, &simple_specs())?),
        "slider" => slider(&Params::parse(params, &slider_specs())?),
        "chain" => chain(&Params::parse(params, &chain_specs())?),
        _ => Err(PluginError::new(
            ErrorKind::UnknownModel,
            name,
            "this plugin offers 'simple', 'slider' and 'chain' ([model] name = ...)",
        )),
    }
}

ssm_api::declare_plugin! {
    name: "pendulum",
    description: "Pendulum family with sin/cos recast (Li, Jain & Haller 2023, Sect. 5.2, App. F)",
    models: models,
    build: build,
}
