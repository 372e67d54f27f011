//! Model parameters: declared with defaults by the plugin, overridden by the
//! scene's `[model.params]` table (passed across the boundary as TOML text).

use std::collections::BTreeMap;

use ssm_api::{ErrorKind, ParamInfo, PluginError, PATH_KIND};

/// Type (and for strings, the allowed values) of a parameter.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ParamKind {
    /// A real number.
    Float,
    /// A non-negative integer.
    Count,
    /// One of a fixed set of strings.
    Choice(&'static [&'static str]),
    /// A file or folder path; the engine reads a relative path from the
    /// scene's folder (it passes the plugin the joined path). The default is
    /// the empty string: not given.
    Path,
    /// A list of exactly this many real numbers, or the empty list (the
    /// default: not given).
    Floats(usize),
}

/// A parameter value.
#[derive(Clone, Debug, PartialEq)]
pub enum ParamValue {
    /// A real number.
    Float(f64),
    /// A non-negative integer.
    Count(u64),
    /// A string.
    Text(String),
    /// A list of real numbers.
    Floats(Vec<f64>),
}

impl std::fmt::Display for ParamValue {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::Float(x) => write!(f, "{x}"),
            Self::Count(x) => write!(f, "{x}"),
            Self::Text(s) => write!(f, "\"{s}\""),
            Self::Floats(v) => {
                let items: Vec<String> = v.iter().map(f64::to_string).collect();
                write!(f, "[{}]", items.join(", "))
            }
        }
    }
}

/// Declaration of one model parameter: name (the paper's symbol), type, default
/// (the paper's value) and a one-line description.
#[derive(Clone, Debug, PartialEq)]
pub struct ParamSpec {
    /// Name as written in scenes.
    pub name: &'static str,
    /// Type.
    pub kind: ParamKind,
    /// Default value.
    pub default: ParamValue,
    /// What it is (with the equation it appears in).
    pub description: &'static str,
}

impl ParamSpec {
    /// A real parameter.
    pub fn float(name: &'static str, default: f64, description: &'static str) -> Self {
        Self {
            name,
            kind: ParamKind::Float,
            default: ParamValue::Float(default),
            description,
        }
    }

    /// A count (non-negative integer) parameter.
    pub fn count(name: &'static str, default: u64, description: &'static str) -> Self {
        Self {
            name,
            kind: ParamKind::Count,
            default: ParamValue::Count(default),
            description,
        }
    }

    /// A parameter taking one of `choices`.
    pub fn choice(
        name: &'static str,
        choices: &'static [&'static str],
        default: &'static str,
        description: &'static str,
    ) -> Self {
        Self {
            name,
            kind: ParamKind::Choice(choices),
            default: ParamValue::Text(default.to_owned()),
            description,
        }
    }

    /// A path parameter (not given by default); relative paths are read from
    /// the scene's folder.
    pub fn path(name: &'static str, description: &'static str) -> Self {
        Self {
            name,
            kind: ParamKind::Path,
            default: ParamValue::Text(String::new()),
            description,
        }
    }

    /// A list of `len` real numbers (not given by default).
    pub fn floats(name: &'static str, len: usize, description: &'static str) -> Self {
        Self {
            name,
            kind: ParamKind::Floats(len),
            default: ParamValue::Floats(Vec::new()),
            description,
        }
    }

    /// The ABI-stable listing of this parameter.
    pub fn info(&self) -> ParamInfo {
        let kind = match self.kind {
            ParamKind::Float => "float".to_owned(),
            ParamKind::Count => "integer".to_owned(),
            ParamKind::Choice(c) => c.join(" | "),
            ParamKind::Path => PATH_KIND.to_owned(),
            ParamKind::Floats(len) => format!("{len} floats"),
        };
        ParamInfo {
            name: self.name.into(),
            kind: kind.into(),
            default: self.default.to_string().into(),
            description: self.description.into(),
        }
    }
}

/// Parsed and validated parameter values (defaults filled in).
#[derive(Clone, Debug, PartialEq)]
pub struct Params {
    values: BTreeMap<&'static str, ParamValue>,
}

impl Params {
    /// Parses the TOML text of `[model.params]` against `specs`: unknown keys,
    /// wrong types, non-finite numbers and values outside a choice are errors
    /// naming the key.
    pub fn parse(toml_text: &str, specs: &[ParamSpec]) -> Result<Self, PluginError> {
        let table: toml::Table = toml_text.parse().map_err(|e: toml::de::Error| {
            PluginError::new(ErrorKind::InvalidParameter, "[model.params]", e.message())
        })?;
        let mut values: BTreeMap<&'static str, ParamValue> =
            specs.iter().map(|s| (s.name, s.default.clone())).collect();
        for (key, value) in &table {
            let Some(spec) = specs.iter().find(|s| s.name == key) else {
                let known: Vec<&str> = specs.iter().map(|s| s.name).collect();
                return Err(PluginError::new(
                    ErrorKind::InvalidParameter,
                    key,
                    &format!("unknown parameter; known: {}", known.join(", ")),
                ));
            };
            let bad = |what: &str| {
                PluginError::new(
                    ErrorKind::InvalidParameter,
                    key,
                    &format!("expected {what}, found {value}"),
                )
            };
            let parsed = match spec.kind {
                ParamKind::Float => {
                    let x = match value {
                        toml::Value::Float(x) => *x,
                        toml::Value::Integer(i) => *i as f64,
                        _ => return Err(bad("a number")),
                    };
                    if !x.is_finite() {
                        return Err(bad("a finite number"));
                    }
                    ParamValue::Float(x)
                }
                ParamKind::Count => match value {
                    toml::Value::Integer(i) if *i >= 0 => ParamValue::Count(*i as u64),
                    _ => return Err(bad("a non-negative integer")),
                },
                ParamKind::Choice(choices) => match value {
                    toml::Value::String(s) if choices.contains(&s.as_str()) => {
                        ParamValue::Text(s.clone())
                    }
                    _ => return Err(bad(&format!("one of {}", choices.join(", ")))),
                },
                ParamKind::Path => match value {
                    toml::Value::String(s) if !s.is_empty() => ParamValue::Text(s.clone()),
                    _ => return Err(bad("a non-empty path string")),
                },
                ParamKind::Floats(len) => {
                    let items = match value {
                        toml::Value::Array(items) if items.is_empty() || items.len() == len => {
                            items
                        }
                        _ => return Err(bad(&format!("a list of {len} numbers"))),
                    };
                    let mut v = Vec::with_capacity(len);
                    for item in items {
                        let x = match item {
                            toml::Value::Float(x) => *x,
                            toml::Value::Integer(i) => *i as f64,
                            _ => return Err(bad(&format!("a list of {len} numbers"))),
                        };
                        if !x.is_finite() {
                            return Err(bad(&format!("a list of {len} finite numbers")));
                        }
                        v.push(x);
                    }
                    ParamValue::Floats(v)
                }
            };
            values.insert(spec.name, parsed);
        }
        Ok(Self { values })
    }

    /// The real value of `name` (a declared float parameter).
    pub fn float(&self, name: &str) -> f64 {
        match self.values.get(name) {
            Some(ParamValue::Float(x)) => *x,
            Some(ParamValue::Count(x)) => *x as f64,
            _ => panic!("parameter '{name}' is not a declared float parameter"),
        }
    }

    /// The integer value of `name` (a declared count parameter).
    pub fn count(&self, name: &str) -> u64 {
        match self.values.get(name) {
            Some(ParamValue::Count(x)) => *x,
            _ => panic!("parameter '{name}' is not a declared count parameter"),
        }
    }

    /// The string value of `name` (a declared choice or path parameter; an
    /// empty path was not given).
    pub fn text(&self, name: &str) -> &str {
        match self.values.get(name) {
            Some(ParamValue::Text(s)) => s,
            _ => panic!("parameter '{name}' is not a declared choice or path parameter"),
        }
    }

    /// The list value of `name` (a declared list parameter; empty when not given).
    pub fn floats(&self, name: &str) -> &[f64] {
        match self.values.get(name) {
            Some(ParamValue::Floats(v)) => v,
            _ => panic!("parameter '{name}' is not a declared list parameter"),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn specs() -> Vec<ParamSpec> {
        vec![
            ParamSpec::float("zeta", 0.01, "damping"),
            ParamSpec::count("n", 3, "bodies"),
            ParamSpec::choice("constraint", &["none", "cubic"], "none", "kind"),
            ParamSpec::path("dir", "model folder"),
            ParamSpec::floats("rayleigh", 2, "alpha, beta"),
        ]
    }

    #[test]
    fn defaults_and_overrides() {
        let p = Params::parse("zeta = 0.5\nconstraint = \"cubic\"", &specs()).unwrap();
        assert_eq!(p.float("zeta"), 0.5);
        assert_eq!(p.count("n"), 3);
        assert_eq!(p.text("constraint"), "cubic");
    }

    #[test]
    fn unknown_key_and_wrong_type_name_the_key() {
        let e = Params::parse("zetta = 1.0", &specs()).unwrap_err();
        assert_eq!(e.context.as_str(), "zetta");
        let e = Params::parse("n = -2", &specs()).unwrap_err();
        assert_eq!(e.context.as_str(), "n");
        let e = Params::parse("constraint = \"round\"", &specs()).unwrap_err();
        assert!(e.message.contains("none, cubic"));
    }

    #[test]
    fn paths_and_lists() {
        let p = Params::parse("dir = \"model\"\nrayleigh = [0.5, 1]", &specs()).unwrap();
        assert_eq!(p.text("dir"), "model");
        assert_eq!(p.floats("rayleigh"), &[0.5, 1.0]);
        let p = Params::parse("rayleigh = []", &specs()).unwrap();
        assert_eq!(p.text("dir"), "");
        assert!(p.floats("rayleigh").is_empty());
        for bad in [
            "rayleigh = [1.0]",
            "rayleigh = [1.0, \"x\"]",
            "rayleigh = 2.0",
            "dir = 3",
            "dir = \"\"",
        ] {
            let e = Params::parse(bad, &specs()).unwrap_err();
            assert_eq!(e.context.as_str(), bad.split(' ').next().unwrap(), "{bad}");
        }
    }
}
