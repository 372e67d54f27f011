//! Reading a model folder (plugin `matrix-model`): the oscillator chain of
//! 10^4 and 10^5 masses written by `ModelFiles::encode` (Matrix Market `M`,
//! `C`, `K`, the cubic springs in `f3.coo`, one output per mass), read back
//! and built into the first-order DAE. Each size first prints the folder's
//! size and checks that the model read equals the plugin's (same matrices,
//! entry for entry), then is timed.
//!
//! Run with `cargo build --release --workspace && cargo bench -p ssm-benches --bench model_files`.

use std::hint::black_box;

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};
use ssm_core::model::plugin::Plugin;
use ssm_tests::{plugin_path, tmp_dir};

fn model_files(c: &mut Criterion) {
    let mut g = c.benchmark_group("model folder read and build");
    g.sample_size(10);
    let chain = Plugin::load(&plugin_path("oscillator-chain")).expect("chain plugin");
    let files = Plugin::load(&plugin_path("matrix-model")).expect("matrix-model plugin");
    for n in [10_000usize, 100_000] {
        let model = chain.build_model("", &format!("n = {n}")).expect("chain");
        let (folder, _) = ssm_plugin_kit::files_from_model(&model).expect("exportable");
        let dir = tmp_dir(&format!("bench-files-{n}"));
        std::fs::create_dir_all(&dir).expect("folder");
        let mut bytes = 0;
        for (name, contents) in folder.encode("bench").expect("encoded") {
            bytes += contents.len();
            std::fs::write(dir.join(name), contents).expect("written");
        }
        let params = format!("dir = {:?}", dir.display().to_string());
        let read = files.build_model("", &params).expect("folder reads");
        assert_eq!(read.a.entries.len(), model.a.entries.len());
        assert_eq!(read.b.entries.len(), model.b.entries.len());
        println!(
            "chain n = {n}: folder of {:.1} MB, {} polynomial terms",
            bytes as f64 / 1e6,
            read.nonlinearity.terms.len()
        );
        g.bench_with_input(BenchmarkId::new("chain", n), &n, |b, _| {
            b.iter(|| black_box(files.build_model("", &params).expect("folder reads")))
        });
        let _ = std::fs::remove_dir_all(&dir);
    }
    g.finish();
}

criterion_group!(benches, model_files);
criterion_main!(benches);
