//! The checks of each spec's values: what a scene's section is checked for
//! (with the same keys and messages) and what a spec built in code must meet
//! before anything runs. Checks that need the model (named outputs and
//! states, a forcing) or a cost estimate are the engine's plan's.

use ssm_kernel::number::{list, short};

use super::{
    BackboneSpec, InvarianceSpec, PodSpec, PodTruncations, ReferenceSpec, ReferenceStart,
    ReportSpec, SimulateSpec, SpecError, SpectrumSpec, SsmSpec, SteadyStateSpec, TransientSpec,
    ValidationSpec, ValidationStart,
};
use crate::fom::hht::load_sampling;
use crate::spectrum::Normalization;

/// Most forcing amplitudes (or frequencies) of a reference, one branch each.
pub const MAX_REFERENCE_CURVES: usize = 8;
/// Most harmonics of a reference.
pub const MAX_HARMONICS: usize = 64;
/// Most continuation steps of one reference branch.
pub const MAX_REFERENCE_STEPS: usize = 100_000;
/// Most samples per sampled run (a CSV of this many rows is already ~100 MB
/// per output).
pub const MAX_SIMULATE_SAMPLES: usize = 2_000_000;
/// Most frequencies of the steady states of `[validate.steady_state]` (each
/// an integration of up to `max_periods` periods; the list is held, and
/// handed around as JSON, before the cost gate runs).
pub const MAX_STEADY_STATES: usize = 10_000;
/// Most reduced models of a POD study (truncations plus SSM pair sets).
pub const MAX_POD_ROMS: usize = 16;
/// Most test runs of a POD study.
pub const MAX_POD_TESTS: usize = 32;

type Checked = Result<(), SpecError>;

fn positive(x: f64, key: &str) -> Checked {
    if x.is_finite() && x > 0.0 {
        Ok(())
    } else {
        Err(SpecError::new(
            key,
            format!("must be a positive number, found {}", short(x)),
        ))
    }
}

fn at_least(n: usize, min: usize, key: &str) -> Checked {
    if n < min {
        return Err(SpecError::new(key, format!("must be at least {min}")));
    }
    Ok(())
}

/// Orders of an answer: at least one, each in `1..=max_order`.
pub(super) fn orders(orders: &[usize], max_order: usize, key: &str) -> Checked {
    if orders.is_empty() {
        return Err(SpecError::new(key, "at least one order is needed".into()));
    }
    if let Some(&bad) = orders.iter().find(|&&o| o < 1 || o > max_order) {
        return Err(SpecError::new(
            key,
            format!("order {bad} is outside 1..={max_order} ([ssm] order)"),
        ));
    }
    Ok(())
}

/// A fraction in `(0, 1)`; `meaning` (e.g. ` (a relative error, 0.01 = 1
/// %)`) follows the range in the message.
fn fraction(x: f64, key: &str, meaning: &str) -> Checked {
    if x.is_finite() && x > 0.0 && x < 1.0 {
        return Ok(());
    }
    Err(SpecError::new(
        key,
        format!("must lie in (0, 1){meaning}, found {}", short(x)),
    ))
}

/// An HHT `alpha` in `[-1/3, 0]`.
fn hht_alpha(a: f64, key: &str) -> Checked {
    if (-1.0 / 3.0..=0.0).contains(&a) {
        return Ok(());
    }
    Err(SpecError::new(
        key,
        format!(
            "must lie in [-1/3, 0] (0: no numerical damping), found {}",
            short(a)
        ),
    ))
}

/// Outputs named, when a list is given: at least one.
fn named(outputs: Option<&Vec<String>>, key: &str) -> Checked {
    if outputs.is_some_and(Vec::is_empty) {
        return Err(SpecError::new(
            key,
            "name at least one output, or leave the key out for [outputs] coordinates".into(),
        ));
    }
    Ok(())
}

/// Amplitudes, one per master pair, each finite and non-negative.
fn amplitudes(rho0: &[f64], pairs: usize) -> bool {
    rho0.len() == pairs && rho0.iter().all(|x| x.is_finite() && *x >= 0.0)
}

/// Phases, one per master pair, each finite.
fn phases(theta0: &[f64], pairs: usize) -> bool {
    theta0.len() == pairs && theta0.iter().all(|t| t.is_finite())
}

/// The first given value that is not a finite number.
fn non_finite(values: &[(String, f64)]) -> Option<&str> {
    values
        .iter()
        .find(|(_, v)| !v.is_finite())
        .map(|(n, _)| n.as_str())
}

impl SsmSpec {
    /// Master pairs 1-based and distinct, an order of at least 1, the
    /// tolerances in `(0, 1)`, a positive eigenvector scale.
    pub fn check(&self) -> Checked {
        let key = "ssm.master_pairs";
        if self.master_pairs.is_empty() {
            return Err(SpecError::new(
                key,
                "at least one master pair is needed".into(),
            ));
        }
        let mut sorted = self.master_pairs.clone();
        sorted.sort_unstable();
        sorted.dedup();
        if sorted.len() != self.master_pairs.len() || sorted[0] == 0 {
            return Err(SpecError::new(
                key,
                "pairs are 1-based and must not repeat".into(),
            ));
        }
        if self.order == Some(0) {
            return Err(SpecError::new("ssm.order", "must be at least 1".into()));
        }
        fraction(self.resonance_tol, "ssm.resonance_tol", "")?;
        fraction(
            self.tolerance,
            "ssm.tolerance",
            " (a relative error, 0.01 = 1 %)",
        )?;
        if let Normalization::Scale(s) = self.normalization {
            if !(s.is_finite() && s > 0.0) {
                return Err(SpecError::new(
                    "ssm.normalization",
                    format!("normalization scale must be a positive number, found {s}"),
                ));
            }
        }
        Ok(())
    }
}

impl SpectrumSpec {
    /// At least one mode, a finite shift.
    pub fn check(&self) -> Checked {
        if self.modes == Some(0) {
            return Err(SpecError::new(
                "spectrum.modes",
                "must be at least 1".into(),
            ));
        }
        if !self.shift.is_finite() {
            return Err(SpecError::new(
                "spectrum.shift",
                format!("must be a finite number, found {}", short(self.shift)),
            ));
        }
        Ok(())
    }
}

impl InvarianceSpec {
    /// Orders up to `max_order`, positive radii, enough sample angles.
    pub fn check(&self, max_order: usize) -> Checked {
        orders(&self.orders, max_order, "outputs.invariance_error.orders")?;
        if self.radii.is_empty() || self.radii.iter().any(|r| !(r.is_finite() && *r > 0.0)) {
            return Err(SpecError::new(
                "outputs.invariance_error.radii",
                "give one or more positive radii".into(),
            ));
        }
        at_least(self.n_alpha, 2, "outputs.invariance_error.n_alpha")?;
        at_least(self.n_theta, 1, "outputs.invariance_error.n_theta")
    }
}

impl BackboneSpec {
    /// One master pair (of `pairs`), a positive `rho_max`, two points or
    /// more, orders up to `max_order`.
    pub fn check(&self, pairs: usize, max_order: usize) -> Checked {
        if pairs != 1 {
            return Err(SpecError::at(
                "outputs.backbone",
                "ssm.master_pairs",
                format!("backbone curves need exactly one master pair, found {pairs}"),
            ));
        }
        positive(self.rho_max, "outputs.backbone.rho_max")?;
        at_least(self.points, 2, "outputs.backbone.points")?;
        match &self.orders {
            Some(o) => orders(o, max_order, "outputs.backbone.orders"),
            None => Ok(()),
        }
    }
}

impl TransientSpec {
    /// A start of `pairs` amplitudes and phases, a positive length, two
    /// samples or more, a tolerance below 1e-2, an order up to `max_order`.
    pub fn check(&self, pairs: usize, max_order: usize) -> Checked {
        if !amplitudes(&self.rho0, pairs) {
            return Err(SpecError::new(
                "outputs.transient.rho0",
                format!("give {pairs} non-negative amplitude(s), one per master pair"),
            ));
        }
        if let Some(th) = &self.theta0 {
            if !phases(th, pairs) {
                return Err(SpecError::new(
                    "outputs.transient.theta0",
                    format!("give {pairs} finite phase(s), one per master pair"),
                ));
            }
        }
        positive(self.t_end, "outputs.transient.t_end")?;
        at_least(self.samples, 2, "outputs.transient.samples")?;
        positive(self.rtol, "outputs.transient.rtol")?;
        if self.rtol >= 1e-2 {
            return Err(SpecError::new(
                "outputs.transient.rtol",
                format!(
                    "must be below 1e-2 (found {}): a looser tolerance lets the step size grow past the oscillation and the transient is wrong",
                    short(self.rtol)
                ),
            ));
        }
        match self.order {
            Some(o) => orders(&[o], max_order, "outputs.transient.order"),
            None => Ok(()),
        }
    }
}

impl ValidationSpec {
    /// The transient's start (`pairs` amplitudes and phases, or finite
    /// given values), length, samples and order (up to `max_order`); the
    /// integrator's tolerances; the steady states (`forced`: the plan has
    /// a forced response to start from).
    pub fn check(&self, pairs: usize, max_order: usize, forced: bool) -> Checked {
        if let Some(t) = &self.transient {
            match &t.start {
                ValidationStart::Ssm { rho0, theta0 } => {
                    if !amplitudes(rho0, pairs) {
                        return Err(SpecError::new(
                            "validate.rho0",
                            format!("give {pairs} non-negative amplitude(s), one per master pair"),
                        ));
                    }
                    if theta0.as_ref().is_some_and(|th| !phases(th, pairs)) {
                        return Err(SpecError::new(
                            "validate.theta0",
                            format!("give {pairs} finite phase(s), one per master pair"),
                        ));
                    }
                }
                ValidationStart::Given { values } => {
                    if let Some(name) = non_finite(values) {
                        return Err(SpecError::new(
                            "validate.x0",
                            format!("'{name}' must be a finite number"),
                        ));
                    }
                }
            }
            positive(t.t_end, "validate.t_end")?;
            at_least(t.samples, 2, "validate.samples")?;
            if let Some(o) = t.order {
                orders(&[o], max_order, "validate.order")?;
            }
        }
        positive(self.rtol, "validate.rtol")?;
        positive(self.atol, "validate.atol")?;
        if self.rtol >= 1e-2 {
            return Err(SpecError::new("validate.rtol", "must be below 1e-2".into()));
        }
        named(self.outputs.as_ref(), "validate.outputs")?;
        match &self.steady_state {
            Some(s) => s.check(forced),
            None => Ok(()),
        }
    }
}

impl SteadyStateSpec {
    /// A positive amplitude, positive frequencies, `delta` in `(0, 1)`,
    /// enough periods and samples, a period multiple of 1 to 8; a start on
    /// the SSM only with a forced response (`forced`).
    pub fn check(&self, forced: bool) -> Checked {
        positive(self.epsilon, "validate.steady_state.epsilon")?;
        if self.omegas.is_empty() || self.omegas.iter().any(|w| !(w.is_finite() && *w > 0.0)) {
            return Err(SpecError::new(
                "validate.steady_state.omega",
                "give one or more positive frequencies".into(),
            ));
        }
        if self.omegas.len() > MAX_STEADY_STATES {
            return Err(SpecError::new(
                "validate.steady_state.omega",
                format!(
                    "give at most {MAX_STEADY_STATES} frequencies, found {}",
                    self.omegas.len()
                ),
            ));
        }
        if self.start == super::SteadyStart::Ssm && !forced {
            return Err(SpecError::new(
                "validate.steady_state.start",
                "start = \"ssm\" starts from the FRC's prediction: add [forcing]".into(),
            ));
        }
        fraction(self.delta, "validate.steady_state.delta", "")?;
        at_least(self.max_periods, 2, "validate.steady_state.max_periods")?;
        let key = "validate.steady_state.max_period_multiple";
        at_least(self.max_period_multiple, 1, key)?;
        if self.max_period_multiple > 8 {
            return Err(SpecError::new(key, "must be at most 8".into()));
        }
        at_least(
            self.samples_per_period,
            4,
            "validate.steady_state.samples_per_period",
        )
    }
}

impl ReportSpec {
    /// Orders up to `max_order`.
    pub fn check(&self, max_order: usize) -> Checked {
        match &self.orders {
            Some(o) => orders(o, max_order, "report.orders"),
            None => Ok(()),
        }
    }
}

impl ReferenceSpec {
    /// Amplitudes and frequencies (this spec's range, else `forcing`'s),
    /// harmonics, step, tolerance and steps within their limits; a start
    /// on the SSM only with a forced response.
    pub fn check(&self, forcing: Option<[f64; 2]>) -> Checked {
        let eps = &self.epsilon;
        if eps.is_empty()
            || eps.len() > MAX_REFERENCE_CURVES
            || eps.iter().any(|e| !(e.is_finite() && *e > 0.0))
        {
            return Err(SpecError::new(
                "reference.epsilon",
                format!(
                    "give 1 to {MAX_REFERENCE_CURVES} positive, finite forcing amplitudes, found {eps:?}"
                ),
            ));
        }
        // without a range of its own, the message points at the amplitudes
        let range_error = |m: String| match self.omega_range {
            Some(_) => SpecError::new("reference.omega_range", m),
            None => SpecError::at("reference.omega_range", "reference.epsilon", m),
        };
        match self.omega_range(forcing) {
            None => return Err(range_error("give omega_range here or in [forcing]".into())),
            Some((lo, hi)) if !(lo.is_finite() && hi.is_finite() && lo > 0.0 && hi > lo) => {
                return Err(range_error(format!(
                    "must be positive, finite and increasing, found {}",
                    list(&[lo, hi])
                )))
            }
            Some(_) => {}
        }
        let h = self.harmonics;
        if !(1..=MAX_HARMONICS).contains(&h) {
            return Err(SpecError::new(
                "reference.harmonics",
                format!("must lie in 1..={MAX_HARMONICS}, found {h}"),
            ));
        }
        let step = self.step;
        if !(step.is_finite() && (1e-4..=10.0).contains(&step)) {
            return Err(SpecError::new(
                "reference.step",
                format!("must lie in [1e-4, 10] (scaled arclength; 0.5 crosses a resonance peak in about 100 steps), found {}", short(step)),
            ));
        }
        let tol = self.tol;
        if !(tol.is_finite() && (1e-14..=1e-3).contains(&tol)) {
            return Err(SpecError::new(
                "reference.tol",
                format!("must lie in [1e-14, 1e-3], found {}", short(tol)),
            ));
        }
        if self.start == Some(ReferenceStart::Ssm) && forcing.is_none() {
            return Err(SpecError::new(
                "reference.start",
                "start = \"ssm\" starts from the reduced model's forced response: add [forcing]"
                    .into(),
            ));
        }
        self.check_amplitude_responses()?;
        let steps = self.max_steps;
        if !(1..=MAX_REFERENCE_STEPS).contains(&steps) {
            return Err(SpecError::new(
                "reference.max_steps",
                format!("must lie in 1..={MAX_REFERENCE_STEPS}, found {steps}"),
            ));
        }
        named(self.outputs.as_ref(), "reference.outputs")?;
        Ok(())
    }

    /// `amplitude_at` and `amplitude_range`.
    fn check_amplitude_responses(&self) -> Checked {
        let w = &self.amplitude_at;
        if w.len() > MAX_REFERENCE_CURVES || w.iter().any(|v| !(v.is_finite() && *v > 0.0)) {
            return Err(SpecError::new(
                "reference.amplitude_at",
                format!(
                    "give 1 to {MAX_REFERENCE_CURVES} positive, finite forcing frequencies, found {w:?}"
                ),
            ));
        }
        if let Some([a, b]) = self.amplitude_range {
            let message = if w.is_empty() {
                Some("traces the amplitude responses of amplitude_at: give the frequencies in amplitude_at".to_owned())
            } else if !(a.is_finite() && b.is_finite() && a >= 0.0 && b > a) {
                Some(format!(
                    "must be finite, non-negative and increasing, found {}",
                    list(&[a, b])
                ))
            } else {
                None
            };
            if let Some(m) = message {
                return Err(SpecError::new("reference.amplitude_range", m));
            }
        }
        Ok(())
    }
}

impl SimulateSpec {
    /// A positive period, 2 to [`MAX_SIMULATE_SAMPLES`] samples over a
    /// finite time, noise in `[0, 1]`, positive tolerances, an HHT `alpha`
    /// in `[-1/3, 0]`, and one run or more, each started on the SSM (`pairs`
    /// amplitudes and phases) or at finite given values.
    pub fn check(&self, pairs: usize) -> Checked {
        positive(self.period, "simulate.period")?;
        let n = self.samples;
        if !(2..=MAX_SIMULATE_SAMPLES).contains(&n) {
            return Err(SpecError::new(
                "simulate.samples",
                format!("must be 2 to {MAX_SIMULATE_SAMPLES}, found {n}"),
            ));
        }
        let span = self.period * (n - 1) as f64;
        if !span.is_finite() {
            return Err(SpecError::new(
                "simulate.period",
                format!("the runs would last {span} (period times samples - 1): not a time"),
            ));
        }
        let noise = self.noise;
        if !(noise.is_finite() && (0.0..=1.0).contains(&noise)) {
            return Err(SpecError::new(
                "simulate.noise",
                format!("must lie in [0, 1] (relative to each output's largest value; 0.01 = 1 %), found {}", short(noise)),
            ));
        }
        positive(self.rtol, "simulate.rtol")?;
        positive(self.atol, "simulate.atol")?;
        if let Some(a) = self.hht_alpha {
            hht_alpha(a, "simulate.hht_alpha")?;
        }
        named(self.outputs.as_ref(), "simulate.outputs")?;
        if self.runs.is_empty() {
            return Err(SpecError::new(
                "simulate.run",
                "give at least one [[simulate.run]] with x0/v0 or rho0".into(),
            ));
        }
        for (k, run) in self.runs.iter().enumerate() {
            let key = format!("simulate.run[{}]", k + 1);
            let problem = match run {
                ValidationStart::Ssm { rho0, theta0 } => {
                    if !amplitudes(rho0, pairs) {
                        Some(format!(
                            "rho0: give {pairs} non-negative amplitude(s), one per master pair"
                        ))
                    } else if theta0.as_ref().is_some_and(|th| !phases(th, pairs)) {
                        Some(format!("theta0: give {pairs} finite phase(s)"))
                    } else {
                        None
                    }
                }
                ValidationStart::Given { values } => {
                    non_finite(values).map(|name| format!("'{name}' must be a finite number"))
                }
            };
            if let Some(m) = problem {
                return Err(SpecError::new(key, m));
            }
        }
        Ok(())
    }
}

impl PodSpec {
    /// Truncations, tolerances, step and `alpha` within their ranges, the
    /// SSM models' pair sets and order, at most [`MAX_POD_ROMS`] models and
    /// [`MAX_POD_TESTS`] tests, and runs of positive length with finite
    /// loads and starts that the fixed step resolves, and load steps at
    /// rising times inside the run.
    pub fn check(&self) -> Checked {
        let n_pod = match &self.truncations {
            PodTruncations::Energy(v) => {
                if v.is_empty() || v.iter().any(|x| !(x.is_finite() && *x > 0.0 && *x < 1.0)) {
                    return Err(SpecError::new(
                        "pod.energy",
                        format!("give fractions in (0, 1) (1e-4: the POMs keep all but 0.01 % of the POVs' sum), found {v:?}"),
                    ));
                }
                v.len()
            }
            PodTruncations::Drop(v) => {
                if v.is_empty() || v.iter().any(|x| !(x.is_finite() && *x > 0.0 && *x <= 16.0)) {
                    return Err(SpecError::new(
                        "pod.drop",
                        format!("give drops in decades in (0, 16], found {v:?}"),
                    ));
                }
                v.len()
            }
        };
        fraction(
            self.rank_tol,
            "pod.rank_tol",
            " (relative to the largest singular value)",
        )?;
        let js = self.jacobian_samples;
        if !(1..=10_000).contains(&js) {
            return Err(SpecError::new(
                "pod.jacobian_samples",
                format!("must be 1 to 10000, found {js}"),
            ));
        }
        if let Some(t) = self.hyper.iter().find(|t| !(**t > 0.0 && **t < 1.0)) {
            return Err(SpecError::new(
                "pod.hyper",
                format!("give DEIM training tolerances in (0, 1), found {t}"),
            ));
        }
        positive(self.step, "pod.step")?;
        hht_alpha(self.hht_alpha, "pod.hht_alpha")?;
        named(self.outputs.as_ref(), "pod.outputs")?;
        for set in &self.ssm_pairs {
            let mut s = set.clone();
            s.sort_unstable();
            s.dedup();
            if s.is_empty() || s.len() != set.len() || s[0] == 0 {
                return Err(SpecError::new(
                    "pod.ssm_pairs",
                    format!("each set lists 1-based master pairs without repeats, found {set:?}"),
                ));
            }
        }
        let models = n_pod * (1 + self.hyper.len()) + self.ssm_pairs.len();
        if models > MAX_POD_ROMS {
            return Err(SpecError::at(
                "pod",
                "pod.step",
                format!("{models} reduced models asked for; at most {MAX_POD_ROMS}"),
            ));
        }
        if let Some(k) = self.ssm_order {
            if !(1..=SsmSpec::AUTO_MAX_ORDER).contains(&k) {
                return Err(SpecError::new(
                    "pod.ssm_order",
                    format!("must be 1 to {}, found {k}", SsmSpec::AUTO_MAX_ORDER),
                ));
            }
        }
        if self.tests.len() > MAX_POD_TESTS {
            return Err(SpecError::new(
                "pod.test",
                format!("at most {MAX_POD_TESTS} test runs"),
            ));
        }
        let runs = std::iter::once(("pod.train".to_owned(), &self.train)).chain(
            self.tests
                .iter()
                .enumerate()
                .map(|(k, r)| (format!("pod.test[{}]", k + 1), r)),
        );
        for (key, r) in runs {
            let bad = |m: String| Err(SpecError::new(key.clone(), m));
            if !(r.t_end.is_finite() && r.t_end > 0.0) {
                return bad(format!("t_end must be positive, found {}", short(r.t_end)));
            }
            if !r.epsilon.is_finite() {
                return bad(format!(
                    "epsilon must be a finite number, found {}",
                    short(r.epsilon)
                ));
            }
            if !(r.omega.is_finite() && r.omega >= 0.0) {
                return bad(format!(
                    "omega must be a non-negative frequency, found {}",
                    short(r.omega)
                ));
            }
            if let Err(m) = load_sampling(self.step, r.omega) {
                return Err(SpecError::new(format!("{key}.omega"), m));
            }
            if let Some(name) = non_finite(&r.start) {
                return bad(format!("'{name}' must be a finite number"));
            }
            load_steps(&r.steps, r.t_end).map_err(|m| SpecError::new(format!("{key}.steps"), m))?;
            if !r.steps.is_empty() && !self.ssm_pairs.is_empty() {
                return Err(SpecError::at(
                    "pod.ssm_pairs",
                    format!("{key}.steps"),
                    "the SSM models' forced terms hold for one constant load amplitude, and a run with load steps changes it: leave out ssm_pairs or the steps".into(),
                ));
            }
        }
        Ok(())
    }
}

/// Most load steps of one POD run.
pub const MAX_LOAD_STEPS: usize = 1000;

/// Load steps `(t_k, a_k)`: at most [`MAX_LOAD_STEPS`], finite factors, and
/// times rising strictly within `[0, t_end)`.
fn load_steps(steps: &[(f64, f64)], t_end: f64) -> Result<(), String> {
    if steps.len() > MAX_LOAD_STEPS {
        return Err(format!(
            "{} load steps; at most {MAX_LOAD_STEPS}",
            steps.len()
        ));
    }
    let mut last = f64::NEG_INFINITY;
    for (k, &(t, a)) in steps.iter().enumerate() {
        if !(t.is_finite() && t >= 0.0 && t < t_end) {
            return Err(format!(
                "step {}: its time {} must lie in [0, t_end = {})",
                k + 1,
                short(t),
                short(t_end)
            ));
        }
        if t <= last {
            return Err(format!(
                "step {}: its time {} does not follow the previous step's {}; give the steps in rising time",
                k + 1,
                short(t),
                short(last)
            ));
        }
        if !a.is_finite() {
            return Err(format!(
                "step {}: its load factor must be a finite number, found {}",
                k + 1,
                short(a)
            ));
        }
        last = t;
    }
    Ok(())
}

#[cfg(test)]
mod load_step_tests {
    use super::load_steps;

    /// Load steps must rise strictly inside `[0, t_end)`, with finite
    /// factors and at most `MAX_LOAD_STEPS` of them; each refusal names the
    /// step.
    #[test]
    fn bad_load_steps_are_refused() {
        assert!(load_steps(&[], 1.0).is_ok());
        assert!(load_steps(&[(0.0, 1.0), (0.5, -2.0)], 1.0).is_ok());
        for (steps, word) in [
            (vec![(0.5, f64::NAN)], "step 1"),
            (vec![(0.2, 1.0), (0.2, 2.0)], "step 2"),
            (vec![(0.5, 1.0), (0.2, 2.0)], "rising"),
            (vec![(1.0, 1.0)], "t_end"),
            (vec![(-0.1, 1.0)], "[0, t_end"),
            (vec![(f64::INFINITY, 1.0)], "step 1"),
        ] {
            let e = load_steps(&steps, 1.0).unwrap_err();
            assert!(e.contains(word), "{steps:?}: {e}");
        }
        let many: Vec<(f64, f64)> = (0..1001).map(|k| (k as f64 * 1e-4, 1.0)).collect();
        assert!(load_steps(&many, 1.0).unwrap_err().contains("at most"));
    }
}
