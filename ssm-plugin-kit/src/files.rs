//! Between a model folder and the mechanical builder: a [`ModelFiles`]
//! becomes a [`MechanicalSystem`] ([`mechanical_from_files`], the plugin
//! `matrix-model`), and a [`Model`] built by the builder becomes a
//! [`ModelFiles`] ([`files_from_model`], `ssm-engine export`).
//!
//! The inverse of the builder's block layout (eqs. 4-5 of Li, Jain & Haller
//! 2023): rows `0..n` hold `C x' + M v' = -K x - f(x) - G(x)^T mu`, rows
//! `n..2n` hold `M x' = M v`, rows `2n..2n+n_c` hold `0 = G0 x + g_nl(x)`.
//!
//! # References
//! M. Li, S. Jain, G. Haller, *Model reduction for constrained mechanical systems
//! via spectral submanifolds*, Nonlinear Dyn. 111 (2023) 8881-8911, eqs. (1)-(5).

use ssm_api::{Harmonic, MechanicalInfo, Model, PolyTerm, PolyVector, SparseMatrix, TimeKind};

use ssm_model_files::{summed, valid_name, ExportError, ModelFiles, NamedOutput};

use crate::mechanical::{Constraints, MechanicalSystem};

/// The mechanical system of the model folder `files`, named `name`, with
/// displacements `x1 .. xn`; `rayleigh = [alpha, beta]` gives
/// `C = alpha M + beta K` when the folder has no `C.mtx`. An error (naming
/// the output) when an output of `outputs.csv` takes the name of a state
/// with another meaning.
pub fn mechanical_from_files(
    files: ModelFiles,
    name: &str,
    rayleigh: Option<[f64; 2]>,
) -> Result<MechanicalSystem, String> {
    let n = files.n_dof();
    let nc = files.n_constraints();
    let dof_names: Vec<String> = (1..=n).map(|i| format!("x{i}")).collect();
    let refs: Vec<&str> = dof_names.iter().map(String::as_str).collect();
    let mut sys = MechanicalSystem::new(name, &refs);
    let damping = match (files.damping, rayleigh) {
        (Some(c), _) => c,
        (None, Some([alpha, beta])) => {
            SparseMatrix::rayleigh(&files.mass, &files.stiffness, alpha, beta)
        }
        (None, None) => SparseMatrix::zeros(n, n),
    };
    sys.damping = damping;
    sys.mass = files.mass;
    sys.stiffness = files.stiffness;
    sys.internal_force = PolyVector {
        n_vars: 2 * n as u32,
        ..files.internal_force
    };
    if let Some(g0) = files.constraint_jacobian {
        let mut g = files.constraint_terms;
        for (j, i, v) in g0.iter() {
            g.push(j, v, &[(i, 1)]);
        }
        sys.constraints = Some(Constraints::polynomial(g));
    }
    if let Some(load) = files.load {
        let mut cos = PolyVector::zeros(n, 2 * n);
        for (i, &f) in load.iter().enumerate() {
            cos.push(i, f, &[]);
        }
        sys.forcing = vec![Harmonic {
            multiple: 1.0,
            cos,
            sin: PolyVector::zeros(n, 2 * n),
        }];
    }
    for (out, weights) in files.outputs {
        if let Some(state) = state_named(&out, n, nc) {
            if weights.len() == 1 && weights[0] == (state, 1.0) {
                continue;
            }
            return Err(format!(
                "output '{out}' is the name of a state of the model (displacements \
                     x1..x{n}, velocities x1_dot.., multipliers mu1..); choose another name"
            ));
        }
        sys.extra_outputs.push((out, weights));
    }
    Ok(sys)
}

/// The model folder of a model the mechanical builder made (the inverse of
/// its block layout); also the notes on what was left out (outputs that read
/// velocities or multipliers). An error when the model is not of that form.
pub fn files_from_model(model: &Model) -> Result<(ModelFiles, Vec<String>), ExportError> {
    let unsupported = |reason: String| ExportError::Unsupported {
        model: model.name.to_string(),
        reason,
    };
    let info = match (model.mechanical.as_ref().into_option(), model.time) {
        (Some(info), TimeKind::Flow) => info,
        _ => {
            return Err(unsupported(
                "it is not a mechanical system (the plugin built it in first-order form \
                     or as a map, not through the mechanical builder)"
                    .to_owned(),
            ))
        }
    };
    if !model.expressions.terms.is_empty() || !model.equilibrium.is_empty() {
        return Err(unsupported(
            "it has non-polynomial terms (recast expressions such as sin) or an \
                 equilibrium away from the origin; the files hold polynomial models about \
                 the origin"
                .to_owned(),
        ));
    }
    let n = info.n_dof as usize;
    let nc = info.n_constraints as usize;
    if *info != MechanicalInfo::canonical(n, nc, info.mass.clone()) {
        return Err(unsupported(
            "its states are not in the builder's order (x, x', mu)".to_owned(),
        ));
    }
    let blocks = Blocks::split(model, n, nc);
    let layout = |what: &str| {
        unsupported(format!(
            "{what} does not have the builder's block form (eq. 5): the model was not \
                 built from (M, C, K, f, g)"
        ))
    };
    if !same(&blocks.b_momentum_v, &info.mass)
        || !same(&blocks.b_kinematic_x, &info.mass)
        || !same(&blocks.a_kinematic_v, &info.mass)
        || !blocks.other.is_empty()
    {
        return Err(layout("A or B"));
    }
    let mut minus_g0t = SparseMatrix::zeros(n, nc);
    for (j, i, v) in blocks.g0.iter() {
        minus_g0t.push(i, j, -v);
    }
    if !same(&blocks.a_momentum_mu, &minus_g0t) {
        return Err(layout("the multiplier columns of A"));
    }
    let (internal_force, constraint_terms) =
        split_nonlinearity(model, n, nc).map_err(&unsupported)?;
    let load = load_shape(model, n).map_err(&unsupported)?;
    let (outputs, notes) = displacement_outputs(model, n, nc);
    let files = ModelFiles {
        mass: info.mass.clone(),
        stiffness: blocks.minus_k,
        damping: Some(blocks.c).filter(|c| !c.entries.is_empty()),
        constraint_jacobian: Some(blocks.g0).filter(|_| nc > 0),
        internal_force,
        constraint_terms,
        load,
        outputs,
    };
    rebuilds(&files, model).map_err(&unsupported)?;
    Ok((files, notes))
}

/// The outputs a folder can name (weighted sums of displacements, under
/// names `outputs.csv` allows and the read-back model does not already
/// give), and a note for each one left out.
fn displacement_outputs(model: &Model, n: usize, nc: usize) -> (Vec<NamedOutput>, Vec<String>) {
    let mut outputs = Vec::new();
    let mut notes = Vec::new();
    for out in model.outputs.iter() {
        let name = out.name.as_str();
        let w: Vec<(usize, f64)> = out
            .weights
            .iter()
            .map(|w| (w.state as usize, w.value))
            .collect();
        let is_state = matches!(w.as_slice(), [(s, v)] if *v == 1.0
            && model.states.get(*s).is_some_and(|st| st.name == out.name));
        let skip = if w.iter().any(|&(s, _)| s >= n) {
            // the read-back model has its own velocity and multiplier states
            (!is_state).then(|| "reads velocities or multipliers".to_owned())
        } else if w.is_empty() {
            Some("has no weights".to_owned())
        } else if !valid_name(name) {
            Some("has a name outputs.csv cannot hold (letters, digits, '_', '.', '-')".to_owned())
        } else {
            match state_named(name, n, nc) {
                Some(s) if w == [(s, 1.0)] => None,
                Some(_) => Some(format!(
                    "is named like a state of the read-back model ({name}) but is another one"
                )),
                None => {
                    outputs.push((name.to_owned(), w));
                    None
                }
            }
        };
        if let Some(why) = skip {
            notes.push(format!("output '{name}' {why}; it is not written"));
        }
    }
    (outputs, notes)
}

/// `Ok` when the folder `files`, read back, builds exactly `model`'s `A`,
/// `B`, `F` and forcing (so nothing the plugin put in the model is lost or
/// changed on the way); what differs otherwise.
fn rebuilds(files: &ModelFiles, model: &Model) -> Result<(), String> {
    let sys = mechanical_from_files(files.clone(), model.name.as_str(), None)?;
    let rebuilt = sys.into_model().map_err(|e| e.to_string())?;
    let differs = |what: &str| {
        Err(format!(
            "{what} would not be rebuilt from the files: the model was not built from \
                 (M, C, K, f(x), g(x), fext) by the mechanical builder"
        ))
    };
    if rebuilt.states.len() != model.states.len() {
        return differs("the number of states");
    }
    for (what, x, y) in [("A", &model.a, &rebuilt.a), ("B", &model.b, &rebuilt.b)] {
        if !same(x, y) {
            return differs(what);
        }
    }
    if model.nonlinearity.clone().canonical() != rebuilt.nonlinearity.clone().canonical() {
        return differs("the nonlinearity F");
    }
    let forcing = |m: &Model| {
        m.forcing
            .iter()
            .map(|h| h.cos.clone().canonical())
            .collect::<Vec<_>>()
    };
    if forcing(model) != forcing(&rebuilt) {
        return differs("the forcing");
    }
    Ok(())
}

/// The blocks of `A` and `B` in the builder's layout.
struct Blocks {
    minus_k: SparseMatrix,
    c: SparseMatrix,
    g0: SparseMatrix,
    b_momentum_v: SparseMatrix,
    b_kinematic_x: SparseMatrix,
    a_kinematic_v: SparseMatrix,
    a_momentum_mu: SparseMatrix,
    /// Entries outside every block the builder fills.
    other: Vec<(usize, usize, f64)>,
}

impl Blocks {
    fn split(model: &Model, n: usize, nc: usize) -> Self {
        let mut b = Blocks {
            minus_k: SparseMatrix::zeros(n, n),
            c: SparseMatrix::zeros(n, n),
            g0: SparseMatrix::zeros(nc, n),
            b_momentum_v: SparseMatrix::zeros(n, n),
            b_kinematic_x: SparseMatrix::zeros(n, n),
            a_kinematic_v: SparseMatrix::zeros(n, n),
            a_momentum_mu: SparseMatrix::zeros(n, nc),
            other: Vec::new(),
        };
        // explicit zeros kept (push_entry): the pattern is part of what the
        // engine factorizes
        let block = |i: usize| (i / n).min(2);
        let local = |i: usize| if i >= 2 * n { i - 2 * n } else { i % n };
        for (i, j, v) in model.a.iter() {
            let (li, lj) = (local(i), local(j));
            match (block(i), block(j)) {
                (0, 0) => b.minus_k.push_entry(li, lj, -v),
                (0, 2) => b.a_momentum_mu.push_entry(li, lj, v),
                (1, 1) => b.a_kinematic_v.push_entry(li, lj, v),
                (2, 0) => b.g0.push_entry(li, lj, v),
                _ => b.other.push((i, j, v)),
            }
        }
        for (i, j, v) in model.b.iter() {
            let (li, lj) = (local(i), local(j));
            match (block(i), block(j)) {
                (0, 0) => b.c.push_entry(li, lj, v),
                (0, 1) => b.b_momentum_v.push_entry(li, lj, v),
                (1, 0) => b.b_kinematic_x.push_entry(li, lj, v),
                _ => b.other.push((i, j, v)),
            }
        }
        b.other.retain(|&(_, _, v)| v != 0.0);
        b
    }
}

/// Equal values at every position (explicit zeros aside).
fn same(a: &SparseMatrix, b: &SparseMatrix) -> bool {
    let nonzero = |m: &SparseMatrix| {
        let mut e = summed(m);
        e.retain(|x| x.2 != 0.0);
        e
    };
    nonzero(a) == nonzero(b)
}

/// `f(x)` from rows `0..n` of `F` (negated; the `-(dg/dx)^T mu` terms, which
/// the builder makes again from `g`, dropped) and `g_nl(x)` from rows `2n..`.
fn split_nonlinearity(
    model: &Model,
    n: usize,
    nc: usize,
) -> Result<(PolyVector, PolyVector), String> {
    let mut f = PolyVector::zeros(n, n);
    let mut g = PolyVector::zeros(nc, n);
    let in_x = |t: &PolyTerm| t.factors.iter().all(|p| (p.var as usize) < n);
    let has_mu = |t: &PolyTerm| t.factors.iter().any(|p| p.var as usize >= 2 * n);
    for t in model.nonlinearity.terms.iter() {
        let eq = t.eq as usize;
        let degree = t.degree();
        let factors: Vec<(usize, u32)> = t
            .factors
            .iter()
            .map(|p| (p.var as usize, p.power))
            .collect();
        if eq < n && has_mu(t) {
            continue;
        }
        if !in_x(t) {
            return Err(format!(
                "equation {} has a term in velocities or multipliers; the files hold f(x) \
                 and g(x) only",
                eq + 1
            ));
        }
        if !(2..=3).contains(&degree) {
            return Err(format!(
                "equation {} has a term of degree {degree}; the files hold degrees 2 and 3 \
                 (f2.coo, f3.coo, g2.coo, g3.coo)",
                eq + 1
            ));
        }
        match eq {
            _ if eq < n => f.push(eq, -t.coeff, &factors),
            _ if eq >= 2 * n => g.push(eq - 2 * n, t.coeff, &factors),
            _ => {
                return Err(format!(
                    "kinematic equation {} has a nonlinear term",
                    eq + 1
                ))
            }
        }
    }
    Ok((f, g))
}

/// The load shape from the forcing `fext cos(Omega t)` with constant `fext`.
fn load_shape(model: &Model, n: usize) -> Result<Option<Vec<f64>>, String> {
    let h = match model.forcing.as_slice() {
        [] => return Ok(None),
        [h] => h,
        _ => {
            return Err(format!(
                "its forcing has {} harmonics; the files hold one, fext cos(Omega t)",
                model.forcing.len()
            ))
        }
    };
    if h.multiple != 1.0 || !h.sin.terms.is_empty() {
        return Err(
            "its forcing is not fext cos(Omega t) (another multiple of Omega, or a sine part)"
                .to_owned(),
        );
    }
    let mut load = vec![0.0; n];
    for t in h.cos.terms.iter() {
        if t.degree() != 0 || t.eq as usize >= n {
            return Err(
                "its forcing depends on the state or enters a kinematic or constraint row; \
                 the files hold a constant load shape"
                    .to_owned(),
            );
        }
        load[t.eq as usize] += t.coeff;
    }
    Ok(Some(load))
}

/// The state index of the builder's state named `name`, if any.
fn state_named(name: &str, n: usize, nc: usize) -> Option<usize> {
    // exactly the names the builder gives: "x7", not "x07"
    let number = |rest: &str, count: usize| {
        rest.parse::<usize>()
            .ok()
            .filter(|&k| (1..=count).contains(&k) && k.to_string() == rest)
    };
    if let Some(rest) = name.strip_prefix("mu") {
        return number(rest, nc).map(|k| 2 * n + k - 1);
    }
    let rest = name.strip_prefix('x')?;
    match rest.strip_suffix("_dot") {
        Some(v) => number(v, n).map(|k| n + k - 1),
        None => number(rest, n).map(|k| k - 1),
    }
}
