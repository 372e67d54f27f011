//! A model's and a reducer's listing from their parameter specs.

use ssm_api::{InputNeeds, ModelInfo, ReducerInfo};

use crate::ParamSpec;

/// The listing of a model with the parameters `specs` (defaults included).
pub fn model_info(name: &str, description: &str, specs: &[ParamSpec]) -> ModelInfo {
    ModelInfo {
        name: name.into(),
        description: description.into(),
        params: specs.iter().map(ParamSpec::info).collect(),
    }
}

/// The listing of a reducer with the parameters `specs` and what it `needs`.
pub fn reducer_info(
    name: &str,
    description: &str,
    specs: &[ParamSpec],
    needs: InputNeeds,
) -> ReducerInfo {
    ReducerInfo {
        name: name.into(),
        description: description.into(),
        params: specs.iter().map(ParamSpec::info).collect(),
        needs,
    }
}
