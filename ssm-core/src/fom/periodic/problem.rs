//! The harmonic balance as a continuation problem: the unknowns are the
//! scaled Fourier coefficients and one parameter, either the forcing
//! frequency (a forced response curve) or the forcing amplitude at a fixed
//! frequency (an amplitude response curve, `R` affine in `eps` with `R_eps =
//! -P Fext`).
//!
//! # References
//! M. Krack, J. Gross, *Harmonic Balance for Nonlinear Vibration Problems*,
//! Springer (2019), Sect. 4.2 (path continuation in any parameter).

use ssm_kernel::continuation::{Monitor, Problem, ProblemFailure, Test};

use super::{floquet, HarmonicBalance, OrbitInfo};

/// The parameter continued along a branch (the last unknown).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Parameter {
    /// The forcing frequency `Omega`, scaled by
    /// [`HarmonicBalance::frequency_scale`].
    Frequency,
    /// The forcing amplitude `eps` at the fixed frequency `omega`, scaled by
    /// [`HarmonicBalance::epsilon_scale`].
    Amplitude {
        /// The fixed forcing frequency.
        omega: f64,
    },
}

impl HarmonicBalance<'_> {
    /// Physical coefficients and frequency of the scaled unknowns `u`, with
    /// the forcing amplitude set from `u` when it is the parameter.
    pub(super) fn load(&mut self, u: &[f64]) -> (Vec<f64>, f64) {
        if let Parameter::Amplitude { .. } = self.parameter {
            self.set_epsilon(u[self.n_coefficients()] * self.epsilon_scale);
        }
        self.unscale(u)
    }

    /// `Omega = ..` or `eps = ..` of the point `u`, for messages.
    fn where_(&self, u: &[f64]) -> String {
        let p = u[self.n_coefficients()];
        match self.parameter {
            Parameter::Frequency => format!("Omega = {}", p * self.frequency_scale),
            Parameter::Amplitude { omega } => {
                format!("Omega = {omega}, eps = {:e}", p * self.epsilon_scale)
            }
        }
    }
}

impl Problem for HarmonicBalance<'_> {
    type Info = OrbitInfo;

    fn dim(&self) -> usize {
        self.n_coefficients() + 1
    }

    fn residual(&mut self, u: &[f64]) -> Result<Vec<f64>, ProblemFailure> {
        let (c, omega) = self.load(u);
        let r = self.residual_physical(&c, omega);
        if r.iter().all(|v| v.is_finite()) {
            Ok(r)
        } else {
            Err(ProblemFailure(format!(
                "the harmonic-balance residual is not finite at {}",
                self.where_(u)
            )))
        }
    }

    fn factor(&mut self, u: &[f64], k: usize) -> Result<(), ProblemFailure> {
        let (c, omega) = self.load(u);
        let vals = self.jacobian_values(&c, omega);
        if !vals.iter().all(|v| v.is_finite()) {
            return Err(ProblemFailure(format!(
                "the harmonic-balance Jacobian is not finite at {}",
                self.where_(u)
            )));
        }
        let at = self.where_(u);
        self.solver
            .factor(&vals, k)
            .map_err(|e| ProblemFailure(format!("harmonic balance at {at}: {}", e.0)))
    }

    fn solve(&mut self, rhs: &mut [f64]) -> Result<(), ProblemFailure> {
        self.solver.solve(rhs)
    }

    /// A branch of period `2T` has rejoined the period-`T` branch where its
    /// odd harmonics (those of `Omega / 2` alone) fall below the floor, or
    /// where they change sign over a step: there the branch crossed the
    /// period-`T` branch at a period doubling and the step landed on the
    /// other half of the pitchfork (the same orbits shifted by `T`).
    fn beyond(&self, last: &[f64], next: &[f64]) -> bool {
        let Some(floor) = self.odd_floor else {
            return false;
        };
        let kk = self.kk();
        let odd: Vec<usize> = (0..self.n_coefficients())
            .filter(|p| {
                let q = p % kk;
                q > 0 && q.div_ceil(2) % 2 == 1
            })
            .collect();
        let norm2: f64 = odd.iter().map(|&p| next[p] * next[p]).sum();
        let turn: f64 = odd.iter().map(|&p| last[p] * next[p]).sum();
        norm2.sqrt() < floor || turn < 0.0
    }

    fn monitor(&mut self, u: &[f64], _t: &[f64]) -> Result<Monitor<OrbitInfo>, ProblemFailure> {
        if !self.stability {
            return Ok(Monitor {
                tests: Vec::new(),
                info: OrbitInfo { floquet: None },
            });
        }
        let (c, omega) = self.load(u);
        let mut structure = self.hill_structure;
        let fl = floquet::floquet_with(self, &c, omega, &mut structure).ok();
        self.hill_structure = structure;
        let tests = tests_of(fl.as_ref());
        Ok(Monitor {
            tests,
            info: OrbitInfo { floquet: fl },
        })
    }
}

/// The test functions of an orbit with Floquet analysis `fl` (none without
/// one): the real multipliers' crossing ([`floquet::Floquet::real_crossing_test`])
/// and the count of complex ones outside the circle.
pub(crate) fn tests_of(fl: Option<&floquet::Floquet>) -> Vec<Test> {
    match fl {
        Some(f) => vec![
            Test::Sign(f.real_crossing_test()),
            Test::Count(f.complex_unstable()),
        ],
        None => Vec::new(),
    }
}

impl OrbitInfo {
    /// Why an orbit's data and test functions `tests`, as read back from a
    /// checkpoint, are not what [`Problem::monitor`] computes: its Floquet
    /// data disagree with themselves (`floquet::Floquet::inconsistency`),
    /// or the tests are not those of its multipliers.
    pub fn restored_inconsistency(&self, tests: &[Test]) -> Option<String> {
        if let Some(why) = self.floquet.as_ref().and_then(|f| f.inconsistency()) {
            return Some(why);
        }
        (tests != tests_of(self.floquet.as_ref()).as_slice())
            .then(|| "its test functions are not those of its multipliers".to_owned())
    }
}
