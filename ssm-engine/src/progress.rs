//! What a run reports while it works: the stage it is in, where a long
//! stage is, each orbit of the full-system reference as it is accepted, and
//! the checkpoint a stopped run resumes from. The pipeline and the analyses
//! report to it; a front end (a terminal display, a binding) implements it.

use ssm_core::fom::periodic::frc::ReferenceOrbit;
use ssm_core::fom::periodic::OrbitInfo;
use ssm_kernel::continuation::Ledger;

/// Stages reported to a progress display.
pub trait Progress {
    /// A new stage begins.
    fn stage(&self, name: &str);
    /// Where a long stage is (e.g. the frequency a continuation reached);
    /// a display may show it in place of the stage's name.
    fn detail(&self, _what: &str) {}
    /// One orbit of the full-system reference (`[reference]`), as it is
    /// accepted, with the names of its output amplitudes: a display may write
    /// it down, so that a run stopped before its outputs are written keeps
    /// what it computed.
    fn reference_orbit(&self, _outputs: &[String], _orbit: &ReferenceOrbit) {}
    /// The ledger of the full-system reference's continuation runs: a
    /// checkpoint that keeps each step, from which a stopped run resumes
    /// (none by default).
    fn checkpoint(&self) -> Option<&dyn Ledger<OrbitInfo>> {
        None
    }
}

/// No progress display.
pub struct Quiet;

impl Progress for Quiet {
    fn stage(&self, _name: &str) {}
}
