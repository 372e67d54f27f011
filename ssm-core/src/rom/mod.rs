//! Answers read off the reduced-order model on the SSM: backbones, the
//! invariance error and lifted transients ([`autonomous`]), forced response
//! curves of one pair ([`frc`], `forced_one_pair`, with error estimates
//! and the accuracy target) and of several pairs by
//! continuation ([`continuation`], [`forced_multi`]); the error estimates
//! of them all from the invariance residual ([`accuracy`]).

pub mod accuracy;
pub mod autonomous;
pub mod continuation;
pub mod forced_multi;
pub(crate) mod forced_one_pair;
pub mod forced_response;
pub mod frc;
pub(crate) mod frc_result;
