//! The reduced transient's file, `rom_trajectory.csv`.

use ssm_core::rom::autonomous::LiftedTransient;

/// `rom_trajectory.csv`: `t,<output>...,rho_1,theta_1,...`.
pub(super) fn transient_csv(tr: &LiftedTransient, outputs: &[String]) -> String {
    let m = tr.polar.first().map_or(0, Vec::len);
    let mut csv = String::from("t");
    for o in outputs {
        csv.push(',');
        csv.push_str(o);
    }
    for i in 1..=m {
        csv.push_str(&format!(",rho_{i},theta_{i}"));
    }
    csv.push('\n');
    for ((t, values), polar) in tr.times.iter().zip(&tr.outputs).zip(&tr.polar) {
        csv.push_str(&format!("{t:.10e}"));
        for y in values {
            csv.push_str(&format!(",{y:.10e}"));
        }
        for (rho, theta) in polar {
            csv.push_str(&format!(",{rho:.10e},{theta:.10e}"));
        }
        csv.push('\n');
    }
    csv
}
