//! The full system's forced responses of `[reference]` (harmonic balance
//! continued in the forcing frequency, with Floquet multipliers): its
//! writers. The reference itself still runs in the pipeline's full-system
//! stage (`pipeline/reference.rs`), after the reduced answers it is seeded
//! from and compared with; the forced response's `frc.svg` draws it.

pub mod write;
