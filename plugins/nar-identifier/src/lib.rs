//! Plugin `nar-identifier`: the NAR identifier reducer of Szalai, Ehrhardt &
//! Haller (2017). From decaying, uniformly sampled signals of one scalar
//! observable it builds the delay embedding (3.1) of dimension `2 nu`, fits
//! the polynomial sampling map (7.1)-(7.2) of order `r` by orthogonal least
//! squares ([`fit`]), and returns it as a discrete-time [`Model`] with period
//! `T` ([`map`]). The engine then computes the SSMs of that map at any order
//! (`F o W = W o R`, Sect. 5), their backbones `omega(rho) = arg(...)/T`
//! (6.5), (6.13) and amplitudes, like those of any other model.
//!
//! Diagnostics (in `summary.json` and `identified.json`): the regression's
//! size, singular values and condition number, the relative residual, the
//! multipliers, the identified frequencies and damping ratios, and the
//! spectral quotients `sigma(E_l)` (5.4), with a warning for each pair whose
//! quotient exceeds the fitted order (the data then do not determine the SSM
//! among the `C^{sigma+1}` manifolds where it is unique, Theorem 5.2).
//!
//! # References
//! R. Szalai, D. Ehrhardt, G. Haller, *Nonlinear model identification and
//! spectral submanifolds for multi-degree-of-freedom mechanical vibrations*,
//! Proc. R. Soc. A 473 (2017) 20160759, Sects. 3-8.

pub mod embedding;
pub mod fit;
pub mod map;

use ssm_api::{
    Diagnostic, ErrorKind, InputNeeds, Model, ModelInfo, PluginError, Reduced, ReducerInfo,
    ReducerInput,
};
use ssm_plugin_kit::{ParamSpec, Params};

use crate::embedding::{MonomialBasis, Series};
use crate::fit::{FitError, FitSettings};

const REDUCER: &str = "nar";

/// Largest number of unknowns (monomials) accepted: the regression matrix
/// has one column each, and beyond this the dense QR takes minutes.
pub const MAX_UNKNOWNS: usize = 5000;

/// Largest regression accepted, in bytes (the matrix and its factors), when
/// the process may use more (see [`ssm_api::limits::memory_room`]): the
/// dense QR holds the matrix whole.
pub const MAX_BYTES: f64 = 2e9;

/// Monomials of degree `1..=order` in `dim` variables,
/// `C(dim + order, order) - 1`, in floating point (exact to 2^53, no
/// overflow for any parameters), computed without building them.
fn monomial_count(dim: usize, order: usize) -> f64 {
    let m = dim.min(order);
    let top = (dim + order) as f64;
    (1..=m).fold(1.0, |acc, i| acc * (top - (m - i) as f64) / i as f64) - 1.0
}

fn specs() -> Vec<ParamSpec> {
    vec![
        ParamSpec::count(
            "nu",
            3,
            "half the embedding dimension: delay vectors of 2 nu samples (3.1); Takens asks nu >= 3",
        ),
        ParamSpec::count(
            "order",
            3,
            "polynomial order r of the sampling map (7.1), monomials of degree 1..r",
        ),
        ParamSpec::float(
            "ridge",
            0.0,
            "Tikhonov parameter relative to the largest singular value of the regression (0: none)",
        ),
        ParamSpec::float(
            "rcond",
            0.0,
            "truncated SVD: singular values below rcond times the largest are dropped (0: none)",
        ),
        ParamSpec::choice(
            "weighting",
            &["uniform", "relative"],
            "uniform",
            "uniform: the residual of (7.2); relative: each delay vector's residual divided by its norm to the power weight_power, so the decaying tail pins the linear part",
        ),
        ParamSpec::float(
            "weight_power",
            1.0,
            "exponent p of the relative weighting 1/|xi|^p, 0 < p <= 4 (1: residuals relative to the delay vector; 2: the small-amplitude tail weighs more, which pins the multipliers and damping ratios against the map's truncation at large amplitude)",
        ),
        ParamSpec::float(
            "floor",
            0.0,
            "delay vectors of norm below floor times the data's largest value are left out (set it a few times above the noise level; 0: none)",
        ),
        ParamSpec::count(
            "decimate",
            1,
            "resampling: every decimate-th sample is used, the map's period is decimate T",
        ),
        ParamSpec::count(
            "skip",
            0,
            "samples dropped at the start of each signal (e.g. a transient off the SSM)",
        ),
    ]
}

fn models() -> Vec<ModelInfo> {
    Vec::new()
}

fn build(name: &str, _params: &str) -> Result<Model, PluginError> {
    ssm_api::select_model(name, &[]).map(|_| unreachable!("no models are offered"))
}

/// The reducer this library offers (`nar`), with its parameters.
pub fn reducers() -> Vec<ReducerInfo> {
    vec![ssm_plugin_kit::reducer_info(
        REDUCER,
        "polynomial sampling map of order r on 2nu-dimensional delay vectors of one observable, fitted by QR/SVD least squares (Szalai, Ehrhardt & Haller 2017, eqs. 3.1, 7.1-7.2)",
        &specs(),
        InputNeeds::Signals,
    )]
}

fn param_err(name: &str, msg: &str) -> PluginError {
    PluginError::new(ErrorKind::InvalidParameter, name, msg)
}

/// The map the reducer `name` (`nar`) identifies from `input`'s signals
/// with the parameters `params` (a TOML table): the plugin's entry point,
/// also called directly by the Python package, which links this library.
///
/// # Errors
/// An unknown reducer or parameter, signals the identification cannot use
/// (too short, too few delay vectors, a rank-deficient fit).
pub fn reduce(name: &str, params: &str, input: &ReducerInput) -> Result<Reduced, PluginError> {
    if name != REDUCER {
        return Err(PluginError::new(
            ErrorKind::UnknownModel,
            name,
            "this plugin offers the reducer 'nar'",
        ));
    }
    let p = Params::parse(params, &specs())?;
    let nu = p.count("nu") as usize;
    let order = p.count("order") as usize;
    let (ridge, rcond) = (p.float("ridge"), p.float("rcond"));
    let decimate = p.count("decimate") as usize;
    let skip = p.count("skip") as usize;
    let floor = p.float("floor");
    if !(floor.is_finite() && (0.0..1.0).contains(&floor)) {
        return Err(param_err(
            "floor",
            "must be in [0, 1) (relative to the data's largest value)",
        ));
    }
    let weight_power = p.float("weight_power");
    if !(weight_power.is_finite() && weight_power > 0.0 && weight_power <= 4.0) {
        return Err(param_err("weight_power", "must be in (0, 4]"));
    }
    let weight_power = if p.text("weighting") == "relative" {
        weight_power
    } else {
        0.0
    };
    if !(1..=16).contains(&nu) {
        return Err(param_err(
            "nu",
            "must be 1 to 16 (delay vectors of 2 to 32 samples)",
        ));
    }
    if !(1..=25).contains(&order) {
        return Err(param_err("order", "must be 1 to 25"));
    }
    if !(ridge.is_finite() && (0.0..1.0).contains(&ridge)) {
        return Err(param_err(
            "ridge",
            "must be in [0, 1) (relative to the largest singular value)",
        ));
    }
    if !(rcond.is_finite() && (0.0..=fit::RCOND_MAX).contains(&rcond)) {
        return Err(param_err(
            "rcond",
            &format!(
                "must be in [0, {}] (singular values below rcond times the largest are dropped: set it near the data's relative noise level, e.g. 1e-10 for simulated data), found {rcond}",
                fit::RCOND_MAX
            ),
        ));
    }
    if decimate == 0 {
        return Err(param_err("decimate", "must be at least 1"));
    }
    let dim = 2 * nu;
    // counted before the basis is built: nu = 16, order = 25 would be
    // 9.9e15 monomials
    let unknowns = monomial_count(dim, order);
    if unknowns > MAX_UNKNOWNS as f64 {
        return Err(param_err(
            "order",
            &format!(
                "nu = {nu}, order = {order}: the monomials of degree 1 to {order} in 2nu = {dim} delay coordinates are {unknowns:.3e} unknowns (at most {MAX_UNKNOWNS}); lower order or nu"
            ),
        ));
    }
    let signals = input.signals.as_ref().into_option().ok_or_else(|| {
        PluginError::new(
            ErrorKind::InvalidInput,
            "data",
            "the NAR identifier needs sampled signals: add a [data] section",
        )
    })?;
    if signals.n_observables() != 1 {
        let names: Vec<&str> = signals.names.iter().map(|s| s.as_str()).collect();
        return Err(PluginError::new(
            ErrorKind::InvalidInput,
            "data.columns",
            &format!(
                "the NAR identifier takes one scalar observable, the data give {} ({}): name one with [data] columns = [\"...\"]",
                names.len(),
                names.join(", ")
            ),
        ));
    }
    if !(signals.period.is_finite() && signals.period > 0.0) {
        return Err(PluginError::new(
            ErrorKind::InvalidInput,
            "data",
            &format!("sampling period {} is not positive", signals.period),
        ));
    }
    let series = Series::new(signals, 0, skip, decimate);
    let rows: usize = (0..series.values.len()).map(|p| series.rows(p, dim)).sum();
    // the regression matrix (rows x unknowns and the right-hand side), then
    // the triangle of its QR and the SVD's factors (about 4 n^2)
    let n = unknowns;
    let bytes = 8.0 * (rows as f64 * (n + 1.0) + 4.0 * n * n);
    let room = ssm_api::limits::memory_room();
    let allowed = (0.75 * room.bytes).min(MAX_BYTES);
    if bytes > allowed {
        return Err(PluginError::new(
            ErrorKind::InvalidInput,
            "data",
            &format!(
                "nu = {nu}, order = {order}: the regression would have {rows} rows by {n} unknowns, about {:.2} GB with its factors; this process may use {:.2} GB (3/4 of the {}, at most {:.0} GB): use decimate or skip, fewer signals, or a lower order or nu",
                bytes / 1e9,
                allowed / 1e9,
                room.source,
                MAX_BYTES / 1e9
            ),
        ));
    }
    let basis = MonomialBasis::new(dim, order);
    let fitted = fit::fit(
        &series,
        &basis,
        &FitSettings {
            dim,
            ridge,
            rcond,
            weight_power,
            floor,
        },
    )
    .map_err(|e| {
        let (kind, ctx) = match &e {
            FitError::ShortSignal { file, .. } => (ErrorKind::InvalidInput, file.clone()),
            FitError::Underdetermined { .. } | FitError::ZeroData | FitError::Scale { .. } => {
                (ErrorKind::InvalidInput, "data".to_owned())
            }
            FitError::RankDeficient { .. } | FitError::NotFinite => {
                (ErrorKind::ReductionFailed, "regression".to_owned())
            }
            FitError::RankTooLow { .. } => (ErrorKind::InvalidParameter, "rcond".to_owned()),
            FitError::Regularized { setting, .. } => {
                (ErrorKind::InvalidParameter, (*setting).to_owned())
            }
        };
        PluginError::new(kind, &ctx, &e.to_string())
    })?;
    let a = map::companion(&basis, &fitted.coefficients);
    let linear = map::linear_figures(&a, series.period).ok_or_else(|| {
        PluginError::new(
            ErrorKind::ReductionFailed,
            "multipliers",
            "the eigenvalues of the identified linear part did not converge",
        )
    })?;
    let largest = linear
        .multipliers
        .iter()
        .map(|m| m.norm())
        .fold(0.0f64, f64::max);
    if largest.is_nan() || largest >= 1.0 {
        let list: Vec<String> = linear
            .multipliers
            .iter()
            .map(|m| format!("{:.6}{:+.6}i (|mu| = {:.6})", m.re, m.im, m.norm()))
            .collect();
        return Err(PluginError::new(
            ErrorKind::ReductionFailed,
            "multipliers",
            &format!(
                "unstable identified map: a multiplier lies on or outside the unit circle, so the fitted origin is not the decaying equilibrium of the data. Multipliers: {}. Use decaying signals, skip their start, lower nu or order, or regularize (ridge)",
                list.join(", ")
            ),
        ));
    }
    let observable = signals.names[0].as_str();
    let model = map::map_model(observable, &basis, &fitted.coefficients, series.period);
    let mut diagnostics = vec![
        Diagnostic::values("embedding_dimension", &[dim as f64]),
        Diagnostic::values("order", &[order as f64]),
        Diagnostic::values("unknowns", &[basis.len() as f64]),
        Diagnostic::values("regression_rows", &[fitted.rows as f64]),
        Diagnostic::values("map_period", &[series.period]),
        Diagnostic::values("data_scale", &[fitted.scale]),
        Diagnostic::values("relative_residual", &[fitted.relative_residual]),
        Diagnostic::values("least_squares_residual", &[fitted.data_residual]),
        Diagnostic::values("condition_number", &[fitted.condition]),
        Diagnostic::values("singular_values", &fitted.singular_values),
        Diagnostic::values("rank_used", &[fitted.rank as f64]),
        Diagnostic::values(
            "multipliers_re_im",
            &linear
                .multipliers
                .iter()
                .flat_map(|m| [m.re, m.im])
                .collect::<Vec<_>>(),
        ),
        Diagnostic::values(
            "frequencies",
            &linear.pairs.iter().map(|p| p.omega).collect::<Vec<_>>(),
        ),
        Diagnostic::values(
            "damping_ratios",
            &linear.pairs.iter().map(|p| p.zeta).collect::<Vec<_>>(),
        ),
        Diagnostic::values(
            "decay_ratios",
            &linear
                .pairs
                .iter()
                .map(|p| p.decay_ratio)
                .collect::<Vec<_>>(),
        ),
        Diagnostic::values(
            "spectral_quotients",
            &linear
                .pairs
                .iter()
                .map(|p| p.spectral_quotient)
                .collect::<Vec<_>>(),
        ),
    ];
    let mut warnings: Vec<(String, String)> = Vec::new();
    for (l, pair) in linear.pairs.iter().enumerate() {
        if pair.spectral_quotient > order as f64 {
            warnings.push((format!("warning_pair_{}", l + 1), format!(
                "pair {}: spectral quotient sigma = {} exceeds the fitted order r = {order}; the SSM is unique only among C^{} manifolds (Theorem 5.2), so terms of the map above order {order} that the data cannot give decide it: treat its backbone beyond the cubic terms as uncertain, or fit order >= {} if the data support it",
                l + 1,
                pair.spectral_quotient,
                pair.spectral_quotient + 1.0,
                pair.spectral_quotient
            )));
        }
    }
    if fitted.condition > 1e8 && ridge == 0.0 && rcond == 0.0 {
        warnings.push(("warning_conditioning".to_owned(), format!(
            "ill-conditioned regression (condition number {:.2e}): the highest-order coefficients are uncertain; consider ridge or rcond",
            fitted.condition
        )));
    }
    for (name, text) in &warnings {
        diagnostics.push(Diagnostic::text(name, text));
    }
    Ok(Reduced {
        model,
        lift: None.into(),
        diagnostics: diagnostics.into_iter().collect(),
    })
}

ssm_api::declare_plugin! {
    name: "nar-identifier",
    description: "NAR identifier: a polynomial sampling map from decaying vibration signals (Szalai, Ehrhardt & Haller 2017)",
    models: models,
    build: build,
    reducers: reducers,
    reduce: reduce,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_unknowns_are_counted_without_building_the_basis() {
        for (dim, order) in [(2, 1), (2, 7), (4, 5), (6, 3), (1, 9)] {
            assert_eq!(
                monomial_count(dim, order),
                MonomialBasis::new(dim, order).len() as f64,
                "2nu = {dim}, order = {order}"
            );
        }
        // nu = 16, order = 25: C(57, 25) - 1
        let c = monomial_count(32, 25);
        assert!((c / 9_929_472_283_517_786.0 - 1.0).abs() < 1e-12, "{c}");
    }
}
