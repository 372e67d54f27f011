//! Answers read off the reduced-order model on the SSM: forced response curves
//! of one pair ([`frc`]) and the continuation of several pairs
//! ([`continuation`]).

pub mod continuation;
pub mod frc;
