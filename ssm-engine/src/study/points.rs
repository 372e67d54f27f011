//! A study's points (a grid, given points, a seeded sample) and the plan
//! and model parameters at a point.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde_json::Value;

use crate::plan::budget::Limits;
use crate::plan::Plan;

/// The sections of a [`Plan`] a point may set a key of (`"frc.epsilon"`),
/// beside `"model.<parameter>"`.
pub const PLAN_SECTIONS: [&str; 10] = [
    "ssm",
    "spectrum",
    "backbone",
    "invariance",
    "transient",
    "frc",
    "validation",
    "reference",
    "report",
    "simulate",
];

/// The most points a study may have.
pub const MAX_POINTS: usize = 10_000_000;

/// Bytes a point of `parameters` parameters holds (its list, each name and
/// value), counted before the points are made.
const fn point_bytes(parameters: usize) -> usize {
    64 + 112 * parameters
}

/// Checks that `count` points of `parameters` parameters fit in `limits`.
///
/// # Errors
/// They would not: the message names the count, the estimate and the limit.
pub fn check_memory(count: usize, parameters: usize, limits: &Limits) -> Result<(), PointsError> {
    let bytes = count as f64 * point_bytes(parameters) as f64;
    if bytes > limits.bytes {
        return Err(PointsError(format!(
            "{count} points of {parameters} parameters need about {:.1} GB, more than the {:.1} GB this process may use ({}); split the study",
            bytes / 1e9,
            limits.bytes / 1e9,
            limits.memory_source
        )));
    }
    Ok(())
}

/// One point: parameter name and value, in order.
pub type Point = Vec<(String, Value)>;

/// The points of a study.
#[derive(Debug, Clone, PartialEq)]
pub struct Points {
    /// One entry per point.
    pub values: Vec<Point>,
    /// For a grid: its parameters and their values, the last varying
    /// fastest.
    pub dims: Option<Vec<(String, Vec<Value>)>>,
}

/// Why a study's points are not valid.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("points: {0}")]
pub struct PointsError(pub String);

/// Checks a parameter's name: `model.<parameter>` or `<section>.<key>`
/// with a section of [`PLAN_SECTIONS`].
///
/// # Errors
/// Any other name.
pub fn check_parameter(name: &str) -> Result<(), PointsError> {
    let (head, rest) = name.split_once('.').unwrap_or((name, ""));
    if rest.is_empty() || rest.contains('.') || !(head == "model" || PLAN_SECTIONS.contains(&head))
    {
        return Err(PointsError(format!(
            "unknown parameter '{name}': give 'model.<parameter>' or '<plan section>.<key>' with a section among {PLAN_SECTIONS:?}"
        )));
    }
    Ok(())
}

/// Checks that `value` is a value a point may give (numbers finite).
fn check_value(name: &str, value: &Value) -> Result<(), PointsError> {
    match value {
        Value::Null => Err(PointsError(format!("'{name}' has no value"))),
        Value::Array(items) => items.iter().try_for_each(|v| check_value(name, v)),
        Value::Object(_) => Err(PointsError(format!(
            "'{name}' is a table; give a number, a string, a boolean or a list"
        ))),
        _ => Ok(()),
    }
}

/// Every combination of the values of `axes` (parameter, values), the last
/// parameter varying fastest.
///
/// # Errors
/// No parameter, an unknown or repeated parameter, an empty list of
/// values, a value that is not a number, string, boolean or list, more
/// than [`MAX_POINTS`] points or more than `limits` hold.
pub fn grid(axes: Vec<(String, Vec<Value>)>, limits: &Limits) -> Result<Points, PointsError> {
    if axes.is_empty() {
        return Err(PointsError("a grid needs at least one parameter".into()));
    }
    let mut count: usize = 1;
    for (i, (name, values)) in axes.iter().enumerate() {
        check_parameter(name)?;
        if axes[..i].iter().any(|(n, _)| n == name) {
            return Err(PointsError(format!("'{name}' is given twice")));
        }
        if values.is_empty() {
            return Err(PointsError(format!("the range of '{name}' is empty")));
        }
        values.iter().try_for_each(|v| check_value(name, v))?;
        count = count
            .checked_mul(values.len())
            .filter(|&c| c <= MAX_POINTS)
            .ok_or_else(|| PointsError(format!("the grid has more than {MAX_POINTS} points")))?;
    }
    check_memory(count, axes.len(), limits)?;
    let mut values = Vec::with_capacity(count);
    for mut k in 0..count {
        let mut point = vec![(String::new(), Value::Null); axes.len()];
        for (slot, (name, vals)) in point.iter_mut().zip(&axes).rev() {
            *slot = (name.clone(), vals[k % vals.len()].clone());
            k /= vals.len();
        }
        values.push(point);
    }
    Ok(Points {
        values,
        dims: Some(axes),
    })
}

/// The points `values` as given.
///
/// # Errors
/// No point, a point with no parameter, an unknown or repeated parameter,
/// a bad value, more than [`MAX_POINTS`] points.
pub fn given(values: Vec<Point>) -> Result<Points, PointsError> {
    if values.is_empty() {
        return Err(PointsError("no point given".into()));
    }
    if values.len() > MAX_POINTS {
        return Err(PointsError(format!("more than {MAX_POINTS} points")));
    }
    for (i, point) in values.iter().enumerate() {
        if point.is_empty() {
            return Err(PointsError(format!("point {i} sets no parameter")));
        }
        for (j, (name, value)) in point.iter().enumerate() {
            check_parameter(name)?;
            if point[..j].iter().any(|(n, _)| n == name) {
                return Err(PointsError(format!("point {i} gives '{name}' twice")));
            }
            check_value(name, value)?;
        }
    }
    Ok(Points { values, dims: None })
}

/// `n` points drawn uniformly from the box `ranges` (parameter, low,
/// high): ChaCha8 seeded with `seed`, the parameters taken in the order of
/// their names, `n` draws each, `low + (high - low) u` with `u` uniform in
/// `[0, 1)` of 53 bits.
///
/// # Errors
/// `n` zero or above [`MAX_POINTS`], no range, an unknown or repeated
/// parameter, a range that is empty or not finite, more points than
/// `limits` hold.
pub fn sample(
    mut ranges: Vec<(String, f64, f64)>,
    n: usize,
    seed: u64,
    limits: &Limits,
) -> Result<Points, PointsError> {
    if n == 0 || n > MAX_POINTS {
        return Err(PointsError(format!(
            "a sample of {n} points (give 1 to {MAX_POINTS})"
        )));
    }
    if ranges.is_empty() {
        return Err(PointsError("a sample needs at least one range".into()));
    }
    ranges.sort_by(|a, b| a.0.cmp(&b.0));
    for (i, (name, low, high)) in ranges.iter().enumerate() {
        check_parameter(name)?;
        if i > 0 && ranges[i - 1].0 == *name {
            return Err(PointsError(format!("'{name}' is given twice")));
        }
        if !(low.is_finite() && high.is_finite() && high > low) {
            return Err(PointsError(format!(
                "the range of '{name}' [{low}, {high}] is empty or not finite"
            )));
        }
    }
    check_memory(n, ranges.len(), limits)?;
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut values = vec![Vec::with_capacity(ranges.len()); n];
    for (name, low, high) in &ranges {
        for point in &mut values {
            let u: f64 = rng.random();
            point.push((name.clone(), Value::from(low + (high - low) * u)));
        }
    }
    Ok(Points { values, dims: None })
}

/// `plan` with the plan values of `point` set (`section.key`; its
/// `model.` parameters are left to the model); a number given for a
/// list-valued key of the forced response (`frc.epsilon`, `frc.orders`)
/// becomes a list of one. The plan is not checked here (the run checks
/// it).
///
/// # Errors
/// A value the plan cannot hold (an unknown key, a wrong type), named.
pub fn plan_at(plan: &Plan, point: &[(String, Value)]) -> Result<Plan, PointsError> {
    let mut value = serde_json::to_value(plan).map_err(|e| PointsError(format!("plan: {e}")))?;
    for (name, v) in point {
        let Some((head, key)) = name.split_once('.') else {
            continue;
        };
        if head == "model" {
            continue;
        }
        let v = match v {
            Value::Number(_) if head == "frc" && matches!(key, "epsilon" | "orders") => {
                Value::Array(vec![v.clone()])
            }
            other => other.clone(),
        };
        let Some(root) = value.as_object_mut() else {
            return Err(PointsError("plan: not a table".into()));
        };
        let section = root
            .entry(head.to_owned())
            .or_insert_with(|| Value::Object(Default::default()));
        if section.is_null() {
            *section = Value::Object(Default::default());
        }
        match section.as_object_mut() {
            Some(table) => {
                table.insert(key.to_owned(), v);
            }
            None => {
                return Err(PointsError(format!(
                    "'{name}': the plan's '{head}' is not a table"
                )))
            }
        }
    }
    serde_json::from_value(value).map_err(|e| PointsError(format!("{}: {e}", names(point))))
}

/// The plan parameters of `point`, for a message.
fn names(point: &[(String, Value)]) -> String {
    let names: Vec<&str> = point
        .iter()
        .map(|(n, _)| n.as_str())
        .filter(|n| !n.starts_with("model."))
        .collect();
    format!("the point's {}", names.join(", "))
}

/// The `model.` parameters of `point`, without the prefix.
pub fn model_params(point: &[(String, Value)]) -> Vec<(String, Value)> {
    point
        .iter()
        .filter_map(|(n, v)| Some((n.strip_prefix("model.")?.to_owned(), v.clone())))
        .collect()
}
