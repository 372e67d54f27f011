//! Scaling of the master eigenvectors, as a scene writes it
//! (`[ssm] normalization`).

use serde::Deserialize;

/// How master eigenvectors are scaled.
///
/// In the scene: `normalization = "unit"`, `"mass"`, or `{ scale = s }`
/// (unit 2-norm times `s > 0`, e.g. to reproduce published coefficients that
/// were computed with another eigenvector scaling).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub enum Normalization {
    /// Unit 2-norm of the whole state vector.
    #[default]
    Unit,
    /// Displacement part mass-normalized, `x^H M x = 1` (needs a mechanical model).
    Mass,
    /// Unit 2-norm times the given positive factor.
    Scale(f64),
}

/// As a scene writes it: `"unit"`, `"mass"` or `{ "scale": s }`.
impl serde::Serialize for Normalization {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        use serde::ser::SerializeMap;
        match self {
            Self::Unit => s.serialize_str("unit"),
            Self::Mass => s.serialize_str("mass"),
            Self::Scale(v) => {
                let mut map = s.serialize_map(Some(1))?;
                map.serialize_entry("scale", v)?;
                map.end()
            }
        }
    }
}

impl<'de> Deserialize<'de> for Normalization {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct Visitor;
        impl<'de> serde::de::Visitor<'de> for Visitor {
            type Value = Normalization;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str(r#""unit", "mass" or { scale = <positive number> }"#)
            }
            fn visit_str<E: serde::de::Error>(self, v: &str) -> Result<Normalization, E> {
                match v {
                    "unit" => Ok(Normalization::Unit),
                    "mass" => Ok(Normalization::Mass),
                    other => Err(E::custom(format!(
                        r#"unknown normalization "{other}"; expected "unit", "mass" or {{ scale = <positive number> }}"#
                    ))),
                }
            }
            fn visit_map<A: serde::de::MapAccess<'de>>(
                self,
                mut map: A,
            ) -> Result<Normalization, A::Error> {
                let mut scale = None;
                while let Some(key) = map.next_key::<String>()? {
                    if key != "scale" {
                        return Err(serde::de::Error::custom(format!(
                            "unknown key `{key}` in normalization; the only key is `scale`"
                        )));
                    }
                    scale = Some(map.next_value::<f64>()?);
                }
                match scale {
                    Some(s) if s.is_finite() && s > 0.0 => Ok(Normalization::Scale(s)),
                    Some(s) => Err(serde::de::Error::custom(format!(
                        "normalization scale must be a positive number, found {s}"
                    ))),
                    None => Err(serde::de::Error::custom(
                        "normalization table needs `scale = <positive number>`",
                    )),
                }
            }
        }
        d.deserialize_any(Visitor)
    }
}
