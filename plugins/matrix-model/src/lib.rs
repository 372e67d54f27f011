//! Plugin `matrix-model`: a mechanical model read from a folder of files
//! (Matrix Market `M`, `K`, `C`, `G0`, sparse quadratic and cubic force and
//! constraint tensors, load shape, named outputs; see `ssm_model_files`),
//! built with the mechanical builder into the first-order DAE of eqs. (4)-(5).
//!
//! So a model from a finite-element code (Abaqus, Ansys, COMSOL, a MATLAB or
//! Python code) runs without writing Rust: `[model] plugin = "matrix-model"`,
//! `[model.params] dir = "my-model"` (read from the scene's folder).
//!
//! # References
//! M. Li, S. Jain, G. Haller, *Model reduction for constrained mechanical systems
//! via spectral submanifolds*, Nonlinear Dyn. 111 (2023) 8881-8911, eqs. (1)-(5).

use std::io::IsTerminal;
use std::path::Path;

use ssm_api::{ErrorKind, Model, ModelInfo, PluginError};
use ssm_model_files::{names, FileError, ModelFiles};
use ssm_plugin_kit::{ParamSpec, Params};

const MODEL: &str = "files";

/// Folders larger than this show a progress bar while they are read (on a terminal).
const PROGRESS_BYTES: u64 = 16 << 20;

fn specs() -> Vec<ParamSpec> {
    vec![
        ParamSpec::path(
            "dir",
            "the model folder (M.mtx, K.mtx, optional C.mtx, G.mtx, f2.coo, f3.coo, g2.coo, g3.coo, fext.mtx, outputs.csv)",
        ),
        ParamSpec::floats(
            "rayleigh",
            2,
            "[alpha, beta]: damping C = alpha M + beta K, for a folder without C.mtx",
        ),
    ]
}

fn models() -> Vec<ModelInfo> {
    vec![ssm_plugin_kit::model_info(
        MODEL,
        "M x'' + C x' + K x + f(x) + G(x)^T mu = eps fext cos(Omega t), g(x) = 0 from files (eqs. 1-2)",
        &specs(),
    )]
}

fn file_error(e: FileError) -> PluginError {
    PluginError::new(ErrorKind::BuildFailed, "model files", &e.to_string())
}

fn build(name: &str, params: &str) -> Result<Model, PluginError> {
    ssm_api::select_model(name, &[MODEL])?;
    let p = Params::parse(params, &specs())?;
    let dir = Path::new(p.text("dir"));
    if dir.as_os_str().is_empty() {
        return Err(PluginError::new(
            ErrorKind::InvalidParameter,
            "dir",
            "required: the folder of the model's files (a relative path is read from the scene's folder)",
        ));
    }
    if !dir.is_dir() {
        return Err(PluginError::new(
            ErrorKind::InvalidParameter,
            "dir",
            &format!("{} is not a folder", dir.display()),
        ));
    }
    let rayleigh = match p.floats("rayleigh") {
        [alpha, beta] => Some([*alpha, *beta]),
        _ => None,
    };
    let files = read_with_progress(dir).map_err(file_error)?;
    if rayleigh.is_some() && files.damping.is_some() {
        return Err(PluginError::new(
            ErrorKind::InvalidParameter,
            "rayleigh",
            &format!(
                "the folder has {} and the scene gives Rayleigh damping; keep one",
                names::C
            ),
        ));
    }
    let sys = ssm_plugin_kit::mechanical_from_files(files, MODEL, rayleigh).map_err(|message| {
        file_error(FileError::Content {
            file: dir.join(names::OUTPUTS),
            message,
        })
    })?;
    sys.into_model().map_err(|e| {
        PluginError::new(
            ErrorKind::BuildFailed,
            &dir.display().to_string(),
            &e.to_string(),
        )
    })
}

/// Reads the folder, with a progress bar for large folders on a terminal.
fn read_with_progress(dir: &Path) -> Result<ModelFiles, FileError> {
    let total: u64 = names::ALL
        .iter()
        .filter_map(|f| std::fs::metadata(dir.join(f)).ok())
        .map(|m| m.len())
        .sum();
    if total < PROGRESS_BYTES || !std::io::stderr().is_terminal() {
        return ModelFiles::read(dir, &mut |_| {});
    }
    let bar = indicatif::ProgressBar::new(total);
    if let Ok(style) = indicatif::ProgressStyle::with_template(
        "reading model files {bar:30} {bytes}/{total_bytes} ({eta})",
    ) {
        bar.set_style(style);
    }
    let mut done = 0u64;
    let mut shown = 0u64;
    let result = ModelFiles::read(dir, &mut |bytes| {
        done += bytes;
        if done - shown > 1 << 20 {
            bar.set_position(done);
            shown = done;
        }
    });
    bar.finish_and_clear();
    result
}

ssm_api::declare_plugin! {
    name: "matrix-model",
    description: "A mechanical model from files: Matrix Market matrices, sparse force tensors, load shape, outputs",
    models: models,
    build: build,
}
