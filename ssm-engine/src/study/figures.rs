//! A point's figures, read off the files its run wrote (`summary.json`,
//! `frc.csv`, `backbone.csv`): what both doors of a study (the command
//! line's `ssm-engine study` and the Python package's `ssm.study`) record.

use serde_json::Value;

use super::store::Cell;

/// Why a run's files do not give its figures.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("figures: {0}")]
pub struct FiguresError(pub String);

/// A CSV table of numbers the engine wrote: its header and its columns.
struct Table {
    names: Vec<String>,
    columns: Vec<Vec<f64>>,
}

impl Table {
    /// Parses `bytes` (a header line, then rows of numbers; an empty or
    /// non-numeric cell is NaN).
    fn parse(name: &str, bytes: &[u8]) -> Result<Table, FiguresError> {
        let text = std::str::from_utf8(bytes).map_err(|e| FiguresError(format!("{name}: {e}")))?;
        let mut lines = text.lines();
        let names: Vec<String> = lines
            .next()
            .ok_or_else(|| FiguresError(format!("{name} is empty")))?
            .split(',')
            .map(str::to_owned)
            .collect();
        let mut columns = vec![Vec::new(); names.len()];
        for line in lines.filter(|l| !l.is_empty()) {
            let cells: Vec<&str> = line.split(',').collect();
            if cells.len() != names.len() {
                return Err(FiguresError(format!(
                    "{name}: a row of {} cells under a header of {}",
                    cells.len(),
                    names.len()
                )));
            }
            for (col, cell) in columns.iter_mut().zip(cells) {
                col.push(cell.trim().parse().unwrap_or(f64::NAN));
            }
        }
        Ok(Table { names, columns })
    }

    fn column(&self, name: &str) -> Option<&[f64]> {
        let j = self.names.iter().position(|n| n == name)?;
        Some(&self.columns[j])
    }
}

/// `x` as Python's `format(x, "g")` writes it (6 significant digits,
/// trailing zeros dropped, an exponent below 1e-4 and from 1e6), so the
/// two doors name columns alike.
pub fn format_g(x: f64) -> String {
    if !x.is_finite() {
        return if x.is_nan() {
            "nan".into()
        } else if x > 0.0 {
            "inf".into()
        } else {
            "-inf".into()
        };
    }
    if x == 0.0 {
        return if x.is_sign_negative() {
            "-0".into()
        } else {
            "0".into()
        };
    }
    let sci = format!("{x:.5e}");
    let (mantissa, exp) = sci.split_once('e').unwrap_or((&sci, "0"));
    let exp: i32 = exp.parse().unwrap_or(0);
    let trim = |s: String| {
        if s.contains('.') {
            s.trim_end_matches('0').trim_end_matches('.').to_owned()
        } else {
            s
        }
    };
    if !(-4..6).contains(&exp) {
        let sign = if exp < 0 { '-' } else { '+' };
        format!("{}e{sign}{:02}", trim(mantissa.to_owned()), exp.abs())
    } else {
        let decimals = usize::try_from(5 - exp).unwrap_or(0);
        trim(format!("{x:.decimals$}"))
    }
}

/// `y(a)` by linear interpolation of the points `(x, y)` (`x` increasing),
/// NaN outside `[x_0, x_last]`, as numpy's `interp` with `left` and
/// `right` NaN.
fn interp(a: f64, x: &[f64], y: &[f64]) -> f64 {
    let (Some(&first), Some(&last)) = (x.first(), x.last()) else {
        return f64::NAN;
    };
    if !(a >= first && a <= last) {
        return f64::NAN;
    }
    if a == last {
        return y[y.len() - 1];
    }
    let k = x.partition_point(|&v| v <= a).max(1) - 1;
    let (x0, x1) = (x[k], x[k + 1]);
    if x1 == x0 {
        return y[k];
    }
    y[k] + (y[k + 1] - y[k]) * (a - x0) / (x1 - x0)
}

/// The rows of `table` whose `order` is `order` (and `epsilon`, within a
/// relative 1e-12, when given).
fn rows(table: &Table, order: f64, epsilon: Option<f64>) -> Vec<usize> {
    let orders = table.column("order").unwrap_or(&[]);
    let eps = table.column("epsilon");
    (0..orders.len())
        .filter(|&i| orders[i] == order)
        .filter(|&i| match (epsilon, eps) {
            (Some(e), Some(col)) => (col[i] - e).abs() <= 1e-12 * e.abs().max(f64::MIN_POSITIVE),
            _ => true,
        })
        .collect()
}

/// The figures of a run from the files it wrote (`files`: name and
/// contents, `summary.json` among them):
/// - per backbone curve of `backbone.csv` (`O<k>_` before the names when
///   there are several orders), its relative frequency shift
///   `omega(rho) / omega(0) - 1` at each amplitude of `backbone_at`
///   (`backbone_shift@<a>`, linear interpolation, NaN beyond the curve);
/// - per forced response curve (`O<k>_` before the names when its curves
///   have several orders): `peak_amplitude` (the first output's
///   largest amplitude) and `peak_omega`, `fold_omegas` and
///   `branch_point_omegas` (sorted), `frc_error_estimate` and
///   `frc_untrusted`;
/// - `backbone_error_estimate` (the largest over the orders) and `order`.
///
/// # Errors
/// `summary.json` is missing or not JSON, a table is malformed.
pub fn figures(
    files: &[(String, Vec<u8>)],
    backbone_at: &[f64],
) -> Result<Vec<(String, Cell)>, FiguresError> {
    let file = |name: &str| {
        files
            .iter()
            .find(|(n, _)| n == name)
            .map(|(_, b)| b.as_slice())
    };
    let summary: Value = serde_json::from_slice(
        file("summary.json").ok_or_else(|| FiguresError("the run wrote no summary.json".into()))?,
    )
    .map_err(|e| FiguresError(format!("summary.json: {e}")))?;
    let mut out = Vec::new();
    if let (false, Some(bytes)) = (backbone_at.is_empty(), file("backbone.csv")) {
        let table = Table::parse("backbone.csv", bytes)?;
        let mut orders: Vec<f64> = table.column("order").unwrap_or(&[]).to_vec();
        orders.sort_by(f64::total_cmp);
        orders.dedup();
        let (rho, omega) = match (table.column("rho"), table.column("omega")) {
            (Some(r), Some(o)) => (r, o),
            _ => {
                return Err(FiguresError(
                    "backbone.csv has no rho or omega column".into(),
                ))
            }
        };
        for &order in &orders {
            let at = rows(&table, order, None);
            let r: Vec<f64> = at.iter().map(|&i| rho[i]).collect();
            let w: Vec<f64> = at.iter().map(|&i| omega[i]).collect();
            let prefix = if orders.len() > 1 {
                format!("O{order}_")
            } else {
                String::new()
            };
            for &a in backbone_at {
                let shift = interp(a, &r, &w) / w[0] - 1.0;
                out.push((
                    format!("{prefix}backbone_shift@{}", format_g(a)),
                    Cell::Float(shift),
                ));
            }
        }
    }
    let frc = &summary["frc"];
    let curves = frc["curves"].as_array().map(Vec::as_slice).unwrap_or(&[]);
    if !curves.is_empty() {
        let table = Table::parse(
            "frc.csv",
            file("frc.csv").ok_or_else(|| FiguresError("the run wrote no frc.csv".into()))?,
        )?;
        let amplitude = table
            .names
            .iter()
            .position(|n| n.ends_with("_linf"))
            .map(|j| &table.columns[j]);
        let omegas = table.column("omega").unwrap_or(&[]);
        let mut orders: Vec<i64> = curves.iter().filter_map(|c| c["order"].as_i64()).collect();
        orders.sort_unstable();
        orders.dedup();
        let bifurcations = frc["bifurcations"]
            .as_array()
            .map(Vec::as_slice)
            .unwrap_or(&[]);
        for c in curves {
            let (order, epsilon) = (
                c["order"].as_f64().unwrap_or(f64::NAN),
                c["epsilon"].as_f64(),
            );
            let prefix = if orders.len() > 1 {
                format!("O{order}_")
            } else {
                String::new()
            };
            let at = rows(&table, order, epsilon);
            if let (Some(amp), Some(&first)) = (amplitude, at.first()) {
                // the first largest, as numpy's argmax
                let k = at
                    .iter()
                    .copied()
                    .fold(first, |k, i| if amp[i] > amp[k] { i } else { k });
                out.push((format!("{prefix}peak_amplitude"), Cell::Float(amp[k])));
                let omega = omegas.get(k).copied().unwrap_or(f64::NAN);
                out.push((format!("{prefix}peak_omega"), Cell::Float(omega)));
            }
            let of_curve = |kind: &str| {
                let mut w: Vec<f64> = bifurcations
                    .iter()
                    .filter(|b| {
                        b["order"] == c["order"]
                            && b["epsilon"] == c["epsilon"]
                            && b["kind"] == kind
                    })
                    .filter_map(|b| b["omega"].as_f64())
                    .collect();
                w.sort_by(f64::total_cmp);
                Cell::List(w)
            };
            out.push((format!("{prefix}fold_omegas"), of_curve("SN")));
            out.push((format!("{prefix}branch_point_omegas"), of_curve("BP")));
            out.push((
                format!("{prefix}frc_error_estimate"),
                c["error_estimate"].as_f64().map_or(Cell::Null, Cell::Float),
            ));
            out.push((
                format!("{prefix}frc_untrusted"),
                Cell::Bool(c["untrusted"].as_bool().unwrap_or(false)),
            ));
        }
    }
    let accuracy = &summary["accuracy"];
    let backbone = accuracy["answers"]
        .as_array()
        .map(Vec::as_slice)
        .unwrap_or(&[])
        .iter()
        .filter(|a| a["answer"] == "backbone")
        .filter_map(|a| a["error_estimate"].as_f64())
        .fold(None, |m: Option<f64>, e| Some(m.map_or(e, |m| m.max(e))));
    if let Some(e) = backbone {
        out.push(("backbone_error_estimate".into(), Cell::Float(e)));
    }
    out.push((
        "order".into(),
        accuracy["order"].as_i64().map_or(Cell::Null, Cell::Int),
    ));
    Ok(out)
}

/// The warnings of a run's `summary.json`.
pub fn warnings(files: &[(String, Vec<u8>)]) -> Vec<String> {
    files
        .iter()
        .find(|(n, _)| n == "summary.json")
        .and_then(|(_, b)| serde_json::from_slice::<Value>(b).ok())
        .and_then(|s| {
            s["warnings"].as_array().map(|w| {
                w.iter()
                    .filter_map(|m| m.as_str().map(str::to_owned))
                    .collect()
            })
        })
        .unwrap_or_default()
}
