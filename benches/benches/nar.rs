//! The NAR identifier (plugin `nar-identifier`): fit of the sampling map,
//! spectrum, SSM and backbone of the identified map, timed as one scene run
//! on data the engine simulates (the catalogue's `shaw_pierre_data` and
//! `chain3_data`). Before timing, each case prints its error against the
//! closed-form linear frequencies of the model that made the data, so
//! speed and error are read side by side.
//!
//! - Shaw-Pierre, Sect. 9a: 2 x 8000 samples, 2 nu = 4, r = 5 (the paper's case);
//! - chain of three oscillators: 3 x 8000 samples, 2 nu = 6, r = 3, 5, 7.
//!
//! Run with `cargo build --release --workspace && cargo bench -p ssm-benches --bench nar`.

use std::hint::black_box;
use std::path::PathBuf;

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};
use ssm_engine::job::run;
use ssm_engine::pipeline::Quiet;
use ssm_engine::scene::SceneFile;
use ssm_tests::{chain3_data, chain_eigenvalues, registry, shaw_pierre_data, tmp_dir};

/// One timed case: label, data files, nu, order, closed-form frequencies.
struct Case<'a> {
    name: &'a str,
    files: &'a [PathBuf],
    nu: usize,
    order: usize,
    exact: Vec<f64>,
}

fn scene(files: &[PathBuf], nu: usize, order: usize) -> SceneFile {
    let list: Vec<String> = files.iter().map(|f| format!("{f:?}")).collect();
    let text = format!(
        "[reduce]\nplugin = \"nar-identifier\"\nreducer = \"nar\"\n[reduce.params]\n\
         nu = {nu}\norder = {order}\nweighting = \"relative\"\nfloor = 1e-5\nrcond = 1e-12\n\
         [data]\nfiles = [{}]\n[ssm]\nmaster_pairs = [1]\norder = {order}\n\
         [outputs]\ncoordinates = [\"x1_dot\"]\n[outputs.backbone]\nrho_max = 0.3\npoints = 31\norders = [{order}]\n",
        list.join(", ")
    );
    SceneFile::parse(std::path::Path::new("bench.toml"), text).expect("scene parses")
}

fn nar(c: &mut Criterion) {
    let mut g = c.benchmark_group("nar identification + SSM + backbone");
    g.sample_size(10);
    let mut reg = registry();
    let sp = shaw_pierre_data(&tmp_dir("bench-nar-sp"), 0.0, 1);
    let chain = chain3_data(&tmp_dir("bench-nar-chain"));
    let chain_w: Vec<f64> = chain_eigenvalues(3, 1.0, 1e-5, 1e-3, 3)
        .iter()
        .map(|l| l.norm())
        .collect();
    let case = |name, files, nu, order, exact| Case {
        name,
        files,
        nu,
        order,
        exact,
    };
    let cases = [
        case("shaw-pierre 2nu=4", &sp, 2, 5, vec![1.0, 3f64.sqrt()]),
        case("chain3 2nu=6", &chain, 3, 3, chain_w.clone()),
        case("chain3 2nu=6", &chain, 3, 5, chain_w.clone()),
        case("chain3 2nu=6", &chain, 3, 7, chain_w),
    ];
    for Case {
        name,
        files,
        nu,
        order,
        exact,
    } in cases
    {
        let s = scene(files, nu, order);
        let r = match run(&s, &mut reg, &Quiet) {
            Ok(r) => r,
            Err(e) => {
                println!("{name}, r = {order}: {e}");
                continue;
            }
        };
        let summary: serde_json::Value =
            serde_json::from_slice(r.outputs.get("summary.json").unwrap()).unwrap();
        let d = &summary["reduction"]["diagnostics"];
        let w: Vec<f64> = d["frequencies"]
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_f64().unwrap())
            .collect();
        let err = exact
            .iter()
            .map(|e| {
                w.iter()
                    .map(|x| ((x - e) / e).abs())
                    .fold(f64::INFINITY, f64::min)
            })
            .fold(0.0, f64::max);
        println!(
            "{name}, r = {order}: {} unknowns, condition {:.1e}, residual {:.1e}, worst linear frequency error {err:.1e}",
            d["unknowns"], d["condition_number"].as_f64().unwrap_or(f64::INFINITY), d["relative_residual"].as_f64().unwrap_or(f64::NAN)
        );
        g.bench_with_input(BenchmarkId::new(name, order), &order, |b, _| {
            b.iter(|| black_box(run(&s, &mut reg, &Quiet).expect("runs")))
        });
    }
    g.finish();
}

criterion_group!(benches, nar);
criterion_main!(benches);
