//! `identified.json`: the model a reducer identified from `[data]` signals
//! (the NAR identifier's sampling map): its linear part, its polynomial
//! terms, the sampling period, and the reducer's diagnostics (residual,
//! conditioning, singular values, frequencies, damping, spectral quotients).

use serde_json::{json, Value};
use ssm_api::TimeKind;

use crate::json::diagnostics;
use ssm_core::model::system::System;
use ssm_core::reduce::Reduction;

/// `identified.json` of the model `sys` made by `r`.
pub(crate) fn identified_json(r: &Reduction, sys: &System) -> String {
    let n = sys.n_states();
    let mut a = vec![vec![0.0; n]; n];
    for (col, row, v) in sys.a.triplet_iter().map(|t| (t.col, t.row, *t.val)) {
        a[row][col] += v;
    }
    let terms: Vec<Value> = sys
        .nonlinearity
        .terms
        .iter()
        .map(|t| {
            let monomial: serde_json::Map<String, Value> = t
                .factors
                .iter()
                .map(|f| (sys.states[f.var as usize].name.to_string(), json!(f.power)))
                .collect();
            json!({
                "equation": sys.states[t.eq as usize].name.as_str(),
                "coefficient": t.coeff,
                "monomial": monomial,
            })
        })
        .collect();
    let value = json!({
        "plugin": r.plugin,
        "reducer": r.reducer,
        "signals": r.signals.as_ref().map(|s| json!({
            "observables": s.names.iter().map(|n| n.as_str()).collect::<Vec<_>>(),
            "period": s.period,
            "files": s.trajectories.iter().map(|t| json!({
                "source": t.source.as_str(),
                "samples": t.samples.len() / s.names.len().max(1),
            })).collect::<Vec<_>>(),
        })),
        "map_period": match sys.time {
            TimeKind::Map { period } => Some(period),
            TimeKind::Flow => None,
        },
        "states": sys.states.iter().map(|s| s.name.as_str()).collect::<Vec<_>>(),
        "linear_part": a,
        "nonlinear_terms": terms,
        "diagnostics": diagnostics(&r.diagnostics),
    });
    serde_json::to_string_pretty(&value).expect("JSON of finite numbers and strings")
}
