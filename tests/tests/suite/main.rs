//! The workspace's integration tests, one module per subject, linked into one
//! test binary (one link of the engine instead of one per file).
//!
//! Run one subject with `cargo test --release -p ssm-tests --test suite fuzz::`.

mod accuracy;
mod ancf;
mod continuation;
mod cost_gate;
mod crank_drive;
mod crank_flexible;
mod crank_housing;
mod damping;
mod divider;
mod docs;
mod examples;
mod frc;
mod full_system_phase;
mod fuzz;
mod fuzz_checkpoints;
mod fuzz_inputs;
mod fuzz_outputs;
mod hht;
mod inputs;
mod layers;
mod limits;
mod model_files;
mod monodromy;
mod nar;
mod nar_models;
mod outputs;
mod pendulum;
mod periodic;
mod plan;
mod plan_run;
mod plate;
mod plugin_boundary;
mod pod;
mod pod_chain;
mod pod_hyper;
mod pod_report;
mod recast;
mod reducers;
mod reference_branches;
mod reference_resume;
mod robustness;
mod scenes;
mod shaw_pierre;
mod simulate;
mod spectrum;
mod ssm_autonomous;
mod study;
mod summary_schema;
mod validation;
mod workspace;
