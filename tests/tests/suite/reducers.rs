//! API 1.x growth and the reducer path, through real `.so` files: a plugin
//! built against the frozen 1.0 layout loads and runs; the modal-truncation
//! fixture reducer proves the path from `[reduce]` to the SSM; a declared
//! constraint layout in another order is read correctly, a contradictory one
//! refused; `[data]` files are read with typed errors.

use ssm_api::{ErrorKind, Model, StateKind};
use ssm_core::model::plugin::{Plugin, PluginLoadError};
use ssm_core::model::system::{ModelError, System};
use ssm_core::reduce::{read_signals, SignalsError};
use ssm_engine::pipeline::JobError;
use ssm_engine::C64;
use ssm_tests::{oscillator_with_spectrum, plugin_path, run_scene_text, spectrum_options, tmp_dir};

/// A plugin whose root module ends at `build_model` (ssm-api 1.0.0) loads in
/// this engine, lists no reducers, and its model runs through the SSM path.
/// Reference: the linear damped oscillator `x'' + 2 zeta x' + x = 0` has
/// `lambda = -zeta + i sqrt(1 - zeta^2)` (closed form), to 1e-12.
#[test]
fn plugin_built_against_api_1_0_loads_and_runs() {
    let p = Plugin::load(&plugin_path("ssm-fixture-api-1-0")).unwrap();
    assert_eq!(p.name(), "api-1.0-fixture");
    assert!(p.reducers().is_none(), "a 1.0 plugin has no reducer entry");
    assert!(matches!(
        p.reduce(
            "x",
            "",
            &ssm_api::ReducerInput {
                model: None.into(),
                signals: None.into()
            }
        ),
        Err(PluginLoadError::NoReducers { .. })
    ));
    let r = run_scene_text(
        "[model]\nplugin = \"api-1.0-fixture\"\n[model.params]\nzeta = 0.03\n[ssm]\norder = 5\n",
    )
    .unwrap();
    let lam = r.masters[0].lambda;
    let exact = C64::new(-0.03, (1.0f64 - 0.03 * 0.03).sqrt());
    assert!((lam - exact).norm() < 1e-12, "{lam} vs {exact}");
    // the cubic term of the backbone is in the reduced dynamics
    let ssm = r.ssm.as_ref().expect("SSM");
    assert!(ssm.r.len() > 1, "{:?}", ssm.r);
}

/// Modal truncation keeps an invariant subspace of the linear part, so the
/// reduced spectrum must equal the kept part of the full spectrum (computed
/// independently by the engine's dense pencil path) to 1e-12 relative.
#[test]
fn modal_truncation_spectrum_is_the_kept_part_of_the_full_one() {
    let (_, full) = oscillator_with_spectrum("none");
    let mut full_pos: Vec<C64> = full
        .eigenvalues
        .iter()
        .copied()
        .filter(|l| l.im > 0.0)
        .collect();
    full_pos.sort_by(|a, b| a.norm().total_cmp(&b.norm()));
    for pairs in [1usize, 2, 3] {
        let r = run_scene_text(&format!(
            "[model]\nplugin = \"spatial-oscillator\"\n[reduce]\nplugin = \"modal-truncation\"\nreducer = \"modal-truncation\"\n[reduce.params]\npairs = {pairs}\n[ssm]\norder = 3\n"
        ))
        .unwrap();
        assert_eq!(r.system.n_states(), 2 * pairs);
        let mut red: Vec<C64> = r
            .spectrum
            .as_ref()
            .expect("spectrum")
            .eigenvalues
            .iter()
            .copied()
            .filter(|l| l.im > 0.0)
            .collect();
        red.sort_by(|a, b| a.norm().total_cmp(&b.norm()));
        assert_eq!(red.len(), pairs);
        for (a, b) in red.iter().zip(&full_pos) {
            assert!(
                (a - b).norm() < 1e-12 * b.norm(),
                "pairs = {pairs}: {a} vs {b}"
            );
        }
        // the outputs of the full model come along, and the summary names the reduction
        assert!(r.system.output("x1").is_some());
        let summary: serde_json::Value =
            serde_json::from_slice(r.outputs.get("summary.json").unwrap()).unwrap();
        assert_eq!(summary["reduction"]["reducer"], "modal-truncation");
        assert_eq!(summary["reduction"]["n_input_states"], 6);
        assert_eq!(summary["reduction"]["n_reduced_states"], 2 * pairs);
        assert_eq!(
            summary["reduction"]["diagnostics"]["dropped_modes"],
            (6 - 2 * pairs) as f64
        );
    }
}

/// Bad reducer scenes name the key: unknown reducer, a reducer that needs a
/// model without [model], a plugin parameter the reducer refuses.
#[test]
fn reducer_scene_errors_name_the_key() {
    let base = "[reduce]\nplugin = \"modal-truncation\"\n";
    let (line, msg) = ssm_tests::scene_error(&format!(
        "[model]\nplugin = \"spatial-oscillator\"\n{base}reducer = \"pod\"\n"
    ));
    assert_eq!(line, 5, "{msg}");
    assert!(
        msg.contains("reduce.reducer") && msg.contains("modal-truncation"),
        "{msg}"
    );
    let (_, msg) = ssm_tests::scene_error(&format!("{base}reducer = \"modal-truncation\"\n"));
    assert!(msg.contains("needs a model"), "{msg}");
    let (line, msg) = ssm_tests::scene_error(&format!(
        "[model]\nplugin = \"spatial-oscillator\"\n{base}reducer = \"modal-truncation\"\n[reduce.params]\npairs = \"many\"\n"
    ));
    assert_eq!(line, 7, "{msg}");
    assert!(msg.starts_with("reduce.params.pairs"), "{msg}");
    // more pairs than the model has is refused, not silently truncated
    let (line, msg) = ssm_tests::scene_error(&format!(
        "[model]\nplugin = \"spatial-oscillator\"\n{base}reducer = \"modal-truncation\"\n[reduce.params]\npairs = 4\n"
    ));
    assert_eq!(line, 7, "{msg}");
    assert!(msg.contains("has 3 underdamped pairs"), "{msg}");
    // a constrained model has constraint modes (B is singular) that a
    // truncation of B^-1 A cannot represent: refused as invalid input
    match run_scene_text(&format!(
        "[model]\nplugin = \"spatial-oscillator\"\n[model.params]\nconstraint = \"cubic\"\n{base}reducer = \"modal-truncation\"\n"
    )) {
        Err(JobError::Plugin(PluginLoadError::Plugin { error, .. })) => {
            assert_eq!(error.kind, ErrorKind::InvalidInput, "{error}");
            assert!(error.message.contains("B is singular"), "{error}");
        }
        other => panic!("expected the reducer's input error, got {other:?}"),
    }
    let (_, msg) = ssm_tests::scene_error("[ssm]\norder = 3\n");
    assert!(msg.contains("[model]") && msg.contains("[reduce]"), "{msg}");
}

/// The spatial oscillator with the cubic constraint, its states and rows
/// permuted (multipliers first, velocities before displacements, constraint
/// rows on top) and the layout declared accordingly, has the same spectrum as
/// the builder's order (reference: the unpermuted model, to 1e-12).
#[test]
fn declared_layout_in_another_order_is_read_correctly() {
    let p = Plugin::load(&plugin_path("spatial-oscillator")).unwrap();
    let model = p.build_model("", "constraint = \"cubic\"").unwrap();
    let n = model.n_states();
    let info = model.mechanical.as_ref().into_option().unwrap().clone();
    let (nd, nc) = (info.n_dof as usize, info.n_constraints as usize);
    // new position of each old state: mu, then x' reversed, then x reversed
    let mut new_of_old = vec![0usize; n];
    for j in 0..nc {
        new_of_old[2 * nd + j] = j;
    }
    for i in 0..nd {
        new_of_old[nd + i] = nc + (nd - 1 - i);
        new_of_old[i] = nc + nd + (nd - 1 - i);
    }
    // rows: constraints first, the rest in order after them
    let mut row_of_old = vec![0usize; n];
    let mut next = nc;
    for (r, row) in row_of_old.iter_mut().enumerate() {
        if r >= 2 * nd && r < 2 * nd + nc {
            *row = r - 2 * nd;
        } else {
            *row = next;
            next += 1;
        }
    }
    let permuted = permute(&model, &new_of_old, &row_of_old);
    let reference = System::from_model("t", model).unwrap();
    let sys = System::from_model("t", permuted).unwrap();
    let opts = spectrum_options(None, 6);
    let (a0, b0) = reference.spectral_pencil();
    let (a1, b1) = sys.spectral_pencil();
    let s0 = ssm_core::spectrum::compute(a0, b0, &opts).unwrap();
    let s1 = ssm_core::spectrum::compute(a1, b1, &opts).unwrap();
    assert_eq!(s0.eigenvalues.len(), 4);
    assert_eq!(s0.eigenvalues.len(), s1.eigenvalues.len());
    for (x, y) in s0.eigenvalues.iter().zip(&s1.eigenvalues) {
        assert!((x - y).norm() < 1e-12 * x.norm(), "{x} vs {y}");
    }
    assert_eq!(sys.states[0].kind, StateKind::Displacement);
    assert_eq!(sys.states[2 * nd].kind, StateKind::Multiplier);
}

/// Permutes a model's states and rows and declares the layout that matches.
fn permute(m: &Model, new_of_old: &[usize], row_of_old: &[usize]) -> Model {
    let mut out = m.clone();
    for t in out.a.entries.iter_mut().chain(out.b.entries.iter_mut()) {
        t.row = row_of_old[t.row as usize] as u32;
        t.col = new_of_old[t.col as usize] as u32;
    }
    for t in out.nonlinearity.terms.iter_mut() {
        t.eq = row_of_old[t.eq as usize] as u32;
        for f in t.factors.iter_mut() {
            f.var = new_of_old[f.var as usize] as u32;
        }
    }
    let mut states = m.states.clone();
    for (old, s) in m.states.iter().enumerate() {
        states[new_of_old[old]] = s.clone();
    }
    out.states = states;
    for o in out.outputs.iter_mut() {
        for w in o.weights.iter_mut() {
            w.state = new_of_old[w.state as usize] as u32;
        }
    }
    let info = out.mechanical.as_mut().into_option().unwrap();
    for list in [
        &mut info.displacements,
        &mut info.velocities,
        &mut info.multipliers,
    ] {
        for k in list.iter_mut() {
            *k = new_of_old[*k as usize] as u32;
        }
    }
    for r in info.constraint_rows.iter_mut() {
        *r = row_of_old[*r as usize] as u32;
    }
    out
}

/// A declared layout that contradicts the state tags, or declares a
/// differential row as a constraint, is refused with what is wrong.
#[test]
fn contradictory_layout_is_refused() {
    let p = Plugin::load(&plugin_path("spatial-oscillator")).unwrap();
    let model = p.build_model("", "constraint = \"cubic\"").unwrap();
    let mut swapped = model.clone();
    {
        let info = swapped.mechanical.as_mut().into_option().unwrap();
        info.displacements[0] = info.velocities[0];
    }
    let err = System::from_model("t", swapped).unwrap_err();
    assert!(matches!(err, ModelError::Layout { .. }), "{err}");
    let msg = err.to_string();
    assert!(
        msg.contains("displacements entry 0") && msg.contains("Velocity"),
        "{msg}"
    );
    let mut differential = model.clone();
    differential
        .mechanical
        .as_mut()
        .into_option()
        .unwrap()
        .constraint_rows[0] = 0;
    let msg = System::from_model("t", differential)
        .unwrap_err()
        .to_string();
    assert!(msg.contains("constraint row 0 has an entry in B"), "{msg}");
    let mut short = model;
    short
        .mechanical
        .as_mut()
        .into_option()
        .unwrap()
        .multipliers
        .pop();
    let msg = System::from_model("t", short).unwrap_err().to_string();
    assert!(
        msg.contains("multipliers lists 0") && msg.contains("expected 1"),
        "{msg}"
    );
}

/// `[data]` files: uniform samples are read; NaN, non-uniform sampling, a
/// missing column, and a ragged row each name the file and line.
#[test]
fn data_files_are_read_with_typed_errors() {
    let dir = tmp_dir("signals");
    std::fs::create_dir_all(&dir).unwrap();
    let write = |name: &str, text: &str| {
        let p = dir.join(name);
        std::fs::write(&p, text).unwrap();
        p
    };
    let good = write("good.csv", "t,v1,v2\n0,1,2\n0.5,3,4\n1.0,5,6\n");
    let s = read_signals(std::slice::from_ref(&good), Some(&["v2".to_owned()])).unwrap();
    assert_eq!(s.period, 0.5);
    assert_eq!(s.n_samples(0), 3);
    assert_eq!(s.sample(0, 2), &[6.0]);
    let nan = write("nan.csv", "t,v1\n0,1\n1,NaN\n");
    let e = read_signals(&[nan], None).unwrap_err();
    assert!(matches!(e, SignalsError::Row { line: 3, .. }), "{e}");
    let uneven = write("uneven.csv", "t,v1\n0,1\n1,1\n2.5,1\n3,1\n");
    let e = read_signals(&[uneven], None).unwrap_err();
    assert!(matches!(e, SignalsError::NonUniform { line: 4, .. }), "{e}");
    let e = read_signals(std::slice::from_ref(&good), Some(&["v9".to_owned()])).unwrap_err();
    assert!(e.to_string().contains("no column 'v9'"), "{e}");
    let ragged = write("ragged.csv", "t,v1\n0,1\n1\n");
    let e = read_signals(&[ragged], None).unwrap_err();
    assert!(matches!(e, SignalsError::Row { line: 3, .. }), "{e}");
    let other_period = write("slow.csv", "t,v1,v2\n0,1,2\n1,3,4\n");
    let e = read_signals(&[good, other_period], None).unwrap_err();
    assert!(e.to_string().contains("sampling period"), "{e}");
}
