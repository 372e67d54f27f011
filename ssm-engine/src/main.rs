//! `ssm-engine`: run a scene, or list plugins.

use std::cell::{Cell, RefCell};
use std::fmt::Write as _;
use std::io::IsTerminal;
use std::io::Write as _;
use std::path::PathBuf;
use std::process::ExitCode;

use clap::{Parser, Subcommand};
use indicatif::{ProgressBar, ProgressStyle};
use ssm_core::fom::periodic::{OrbitInfo, ReferenceOrbit};
use ssm_core::model::plugin::Registry;
use ssm_engine::analyses;
use ssm_engine::job::source::scene_inputs;
use ssm_engine::job::{self, export};
use ssm_engine::output::check_not_input;
use ssm_engine::output::checkpoint::{create_first, Checkpoint};
use ssm_engine::pipeline::Progress;
use ssm_engine::scene::{ReportSection, SceneFile};
use ssm_engine::study::{self, StudyFile};
use ssm_kernel::continuation::Ledger;

/// Counts the heap, for the memory `summary.json` reports.
#[global_allocator]
static HEAP: ssm_kernel::heap::Counting = ssm_kernel::heap::Counting;

const SCENE_HELP: &str = concat!(
    "SCENE FORMAT (TOML; unknown keys are rejected, errors name the line and key):\n\n",
    include_str!("scene/format.toml"),
    "\n\
OUTPUTS (in --out DIR, default ./out/<scene file stem>): summary.json, spectrum.csv,
backbone.csv/.svg, rom_trajectory.csv, frc.csv/.svg, validation.csv/.svg,
steady_state.csv (also drawn into frc.svg), report.csv/.md/.svg, identified.json,
data_backbone.csv, simulation_<k>.csv (as requested).
While a [reference] runs, <out>.reference-partial.csv (its orbits) and
<out>.reference-checkpoint.jsonl (its continuation) are written beside DIR; after a stop,
--resume goes on from the checkpoint to the outputs of an uninterrupted run.
The new result set replaces the old one as a whole (a fresh private directory swapped in
with one rename): never a mix, never stale files; a failed run changes nothing. A non-empty
directory that is not a result set is never replaced, a model export (export DIR) and a
run's result set never replace each other, and an output directory that is or holds an
input of the run (the scene, [data] files, a model folder, a plugin, a checkpoint) is refused.

PLUGINS are found from --plugin PATH, from SSM_PLUGIN_PATH (':'-separated files or
directories), and from the directory of this binary."
);

#[derive(Parser)]
#[command(
    name = "ssm-engine",
    version,
    about = "Nonlinear model reduction on spectral submanifolds (SSMs) for mechanical systems and DAEs",
    after_help = SCENE_HELP
)]
struct Cli {
    /// Load a plugin library (repeatable).
    #[arg(long = "plugin", value_name = "PATH", global = true)]
    plugins: Vec<PathBuf>,
    /// Scene file to run.
    #[arg(value_name = "SCENE.toml")]
    scene: Option<PathBuf>,
    /// Output directory (default ./out/<scene name>).
    #[arg(long, value_name = "DIR")]
    out: Option<PathBuf>,
    /// Resume a stopped run's full-system reference from its checkpoint
    /// <out>.reference-checkpoint.jsonl beside the output directory: the
    /// continuation runs it kept are restored, the rest computed, and the
    /// outputs are those of an uninterrupted run.
    #[arg(long, global = true)]
    resume: bool,
    /// Resume from this checkpoint (e.g. one a run wrote under its process
    /// id because another was in the way).
    #[arg(long, value_name = "FILE", global = true)]
    resume_from: Option<PathBuf>,
    #[command(subcommand)]
    command: Option<Command>,
}

#[derive(Subcommand)]
enum Command {
    /// List every plugin found, its version, and its models with parameters and defaults.
    Plugins,
    /// Run a scene with its speed-against-error report (report.csv, report.md,
    /// report.svg), whether or not the scene has a [report] section.
    Report {
        /// Scene file to run.
        #[arg(value_name = "SCENE.toml")]
        scene: PathBuf,
        /// Output directory (default ./out/<scene name>).
        #[arg(long, value_name = "DIR")]
        out: Option<PathBuf>,
    },
    /// Write the mechanical model of a scene's [model] as a model folder
    /// (M.mtx, K.mtx, C.mtx, G.mtx, f2/f3/g2/g3.coo, fext.mtx, outputs.csv) that
    /// the plugin matrix-model reads back; DIR is replaced as a whole.
    Export {
        /// Scene file whose [model] is written.
        #[arg(value_name = "SCENE.toml")]
        scene: PathBuf,
        /// Folder to write (created; an earlier export there is replaced).
        #[arg(value_name = "DIR")]
        dir: PathBuf,
    },
    /// Print the JSON Schema of summary.json (docs/summary.schema.json).
    Schema,
    /// Run a study (a base scene at many points: a grid, given points or a
    /// seeded sample; docs/studies.md): every point, or one slice of them
    /// for one task of a job array (--shard I/N), each finished point
    /// written at once to the store; points the store holds are skipped.
    /// --merge gathers the store into DIR/table.parquet.
    Study {
        /// Study file.
        #[arg(value_name = "STUDY.toml")]
        study: PathBuf,
        /// Store directory (created; a store of another study is refused).
        #[arg(long, value_name = "DIR")]
        store: PathBuf,
        /// Run the I-th of N slices of the points (1 <= I <= N; e.g.
        /// $SLURM_ARRAY_TASK_ID/4 with sbatch --array=1-4).
        #[arg(long, value_name = "I/N", conflicts_with = "merge")]
        shard: Option<String>,
        /// Gather the store's records into one table (every point must have
        /// its record).
        #[arg(long)]
        merge: bool,
    },
}

impl Command {
    /// The command's word on the command line.
    fn name(&self) -> &'static str {
        match self {
            Command::Plugins => "plugins",
            Command::Report { .. } => "report",
            Command::Export { .. } => "export",
            Command::Schema => "schema",
            Command::Study { .. } => "study",
        }
    }
}

/// Progress of a run: a spinner on a terminal, else one line per stage on
/// stderr (so logs of long runs show where the time goes).
enum Spinner {
    Bar(ProgressBar),
    Lines(std::time::Instant),
}

impl Progress for Spinner {
    fn stage(&self, name: &str) {
        match self {
            Spinner::Bar(bar) => bar.set_message(name.to_owned()),
            Spinner::Lines(t0) => eprintln!("[{:8.2} s] {name}", t0.elapsed().as_secs_f64()),
        }
    }

    fn detail(&self, what: &str) {
        if let Spinner::Bar(bar) = self {
            bar.set_message(what.to_owned());
        }
    }
}

/// The full-system reference's orbits written down as they are accepted,
/// beside the output directory (`<out>.reference-partial.csv`, or with the
/// process id when that exists: an earlier stopped run's, or a concurrent
/// one's), so that a run stopped before its outputs are written keeps them.
/// Created with the first orbit, never over an existing file or through a
/// link; removed once the run's outputs are written.
struct Journal {
    path: Option<PathBuf>,
    file: RefCell<Option<(PathBuf, std::fs::File)>>,
    failed: Cell<bool>,
}

impl Journal {
    fn beside(out: &std::path::Path) -> Self {
        let path = out
            .file_name()
            .map(|n| out.with_file_name(format!("{}.reference-partial", n.to_string_lossy())));
        Journal {
            path,
            file: RefCell::new(None),
            failed: Cell::new(false),
        }
    }

    fn open(&self, header: &str) -> Option<(PathBuf, std::fs::File)> {
        let base = self.path.as_ref()?;
        let candidates = [
            PathBuf::from(format!("{}.csv", base.display())),
            PathBuf::from(format!("{}.{}.csv", base.display(), std::process::id())),
        ];
        create_first(&candidates, header)
            .map_err(|(path, e)| {
                eprintln!(
                    "warning: cannot write the reference's orbits as they go to {}: {e}",
                    path.display()
                );
            })
            .ok()
    }

    fn record(&self, outputs: &[String], orbit: &ReferenceOrbit) {
        if self.failed.get() {
            return;
        }
        let mut slot = self.file.borrow_mut();
        if slot.is_none() {
            *slot = self.open(&analyses::reference::write::orbit_header(outputs));
            if slot.is_none() {
                self.failed.set(true);
                return;
            }
        }
        if let Some((_, f)) = slot.as_mut() {
            if f.write_all(analyses::reference::write::orbit_row(orbit).as_bytes())
                .is_err()
            {
                self.failed.set(true);
            }
        }
    }

    /// The journal's path, if one was written.
    fn written(&self) -> Option<PathBuf> {
        self.file.borrow().as_ref().map(|(p, _)| p.clone())
    }

    /// The default journal `<out>.reference-partial.csv`.
    fn default_path(&self) -> Option<PathBuf> {
        self.path
            .as_ref()
            .map(|p| PathBuf::from(format!("{}.csv", p.display())))
    }

    /// The journal a resumed run keeps, whatever its end: its own went
    /// under its process id when the stopped run's was in the way, and
    /// it replays the stopped run's orbits (restored in the same order)
    /// before its own, so whichever of the two holds more is the whole
    /// record; it takes the default name and the other is removed. So
    /// resumes that fail again leave one journal, not one more each.
    fn settle_resumed(&self) -> Option<PathBuf> {
        let written = self.written()?;
        let Some(default) = self.default_path().filter(|d| *d != written) else {
            return Some(written);
        };
        let size = |p: &std::path::Path| {
            std::fs::symlink_metadata(p)
                .ok()
                .filter(|m| m.file_type().is_file())
                .map(|m| m.len())
        };
        match (size(&written), size(&default)) {
            (Some(new), Some(old)) if new < old => {
                let _ = std::fs::remove_file(&written);
                Some(default)
            }
            (Some(_), Some(_)) => match std::fs::rename(&written, &default) {
                Ok(()) => Some(default),
                Err(_) => Some(written),
            },
            _ => Some(written),
        }
    }
}

/// The spinner, the reference journal and its checkpoint.
struct Display {
    spinner: Spinner,
    journal: Journal,
    checkpoint: Checkpoint,
}

impl Progress for Display {
    fn stage(&self, name: &str) {
        self.spinner.stage(name);
    }

    fn detail(&self, what: &str) {
        self.spinner.detail(what);
    }

    fn reference_orbit(&self, outputs: &[String], orbit: &ReferenceOrbit) {
        self.journal.record(outputs, orbit);
    }

    fn checkpoint(&self) -> Option<&dyn Ledger<OrbitInfo>> {
        Some(&self.checkpoint)
    }
}

impl Spinner {
    fn finish(&self) {
        if let Spinner::Bar(bar) = self {
            bar.finish_and_clear();
        }
    }
}

fn spinner() -> Spinner {
    let interactive = std::io::stderr().is_terminal() && std::env::var_os("CI").is_none();
    if !interactive {
        return Spinner::Lines(std::time::Instant::now());
    }
    let bar = ProgressBar::new_spinner();
    bar.set_style(
        ProgressStyle::with_template("{spinner} {elapsed} {msg}").expect("valid template"),
    );
    bar.enable_steady_tick(std::time::Duration::from_millis(100));
    Spinner::Bar(bar)
}

/// The listing of `ssm-engine plugins`.
fn plugin_listing(registry: &Registry) -> Result<String, std::fmt::Error> {
    let mut s = String::new();
    if registry.plugins.is_empty() {
        writeln!(
            s,
            "no plugins found (pass --plugin PATH or set SSM_PLUGIN_PATH)"
        )?;
    }
    for (path, p) in &registry.plugins {
        writeln!(s, "{} {} ({})", p.name(), p.version(), path.display())?;
        writeln!(s, "  {}", p.description())?;
        match p.models() {
            Ok(models) => {
                for m in models {
                    writeln!(s, "  model '{}': {}", m.name, m.description)?;
                    for par in m.params.iter() {
                        writeln!(
                            s,
                            "    {:<12} = {:<10} [{}] {}",
                            par.name, par.default, par.kind, par.description
                        )?;
                    }
                }
            }
            Err(e) => writeln!(s, "  cannot list models: {e}")?,
        }
        match p.reducers() {
            None => writeln!(s, "  (built against ssm-api 1.0: no reducers)")?,
            Some(Ok(reducers)) => {
                for r in reducers {
                    writeln!(
                        s,
                        "  reducer '{}' (needs {:?}): {}",
                        r.name, r.needs, r.description
                    )?;
                    for par in r.params.iter() {
                        writeln!(
                            s,
                            "    {:<12} = {:<10} [{}] {}",
                            par.name, par.default, par.kind, par.description
                        )?;
                    }
                }
            }
            Some(Err(e)) => writeln!(s, "  cannot list reducers: {e}")?,
        }
    }
    for e in &registry.rejected {
        writeln!(s, "not loadable: {e}")?;
    }
    Ok(s)
}

/// Prints the plugin listing.
fn list_plugins(registry: &Registry) -> anyhow::Result<()> {
    print_text(&plugin_listing(registry)?)
}

/// Writes `text` to stdout; a closed pipe (`ssm-engine plugins | head -1`)
/// ends it quietly.
fn print_text(text: &str) -> anyhow::Result<()> {
    use std::io::Write;
    match std::io::stdout().lock().write_all(text.as_bytes()) {
        Err(e) if e.kind() != std::io::ErrorKind::BrokenPipe => Err(e.into()),
        _ => Ok(()),
    }
}

fn run(cli: Cli) -> anyhow::Result<()> {
    // the global options (--plugin, --resume) may come before a command; a
    // scene or --out may not
    if let (Some(command), Some(_), _) | (Some(command), _, Some(_)) =
        (&cli.command, &cli.scene, &cli.out)
    {
        anyhow::bail!(
            "'{}' takes no scene and no --out before it: ssm-engine SCENE.toml [--out DIR], or ssm-engine [--plugin PATH] {}",
            command.name(),
            command.name()
        );
    }
    // a resumed reference belongs to a run; these commands run none
    if let Some(
        command @ (Command::Plugins
        | Command::Schema
        | Command::Export { .. }
        | Command::Study { .. }),
    ) = &cli.command
    {
        if cli.resume || cli.resume_from.is_some() {
            anyhow::bail!(
                "'{}' runs no scene: --resume and --resume-from go with ssm-engine SCENE.toml or ssm-engine report SCENE.toml",
                command.name()
            );
        }
    }
    if let Some(Command::Schema) = cli.command {
        return print_text(&ssm_engine::output::summary::schema_json());
    }
    let mut registry = Registry::discover(&cli.plugins)?;
    let resume = match (cli.resume_from, cli.resume) {
        (Some(p), _) => Some(Some(p)),
        (None, true) => Some(None),
        (None, false) => None,
    };
    let (scene_path, out, report) = match cli.command {
        Some(Command::Plugins) => return list_plugins(&registry),
        // printed before the plugins were looked for
        Some(Command::Schema) => return Ok(()),
        Some(Command::Report { scene, out }) => (scene, out, true),
        Some(Command::Study {
            study,
            store,
            shard,
            merge,
        }) => return run_study(&study, &store, shard.as_deref(), merge, &mut registry),
        Some(Command::Export { scene, dir }) => {
            let scene = SceneFile::load(&scene)?;
            check_not_input(&dir, &scene_inputs(&scene, &mut registry))?;
            let (files, notes) = export::export(&scene, &mut registry)?;
            files.write(&dir)?;
            for note in notes {
                eprintln!("note: {note}");
            }
            println!("{}: wrote the model files to {}", scene.name(), dir.display());
            return Ok(());
        }
        None => match cli.scene {
            Some(s) => (s, cli.out, false),
            None => anyhow::bail!(
                "no scene given: ssm-engine SCENE.toml [--out DIR], ssm-engine report SCENE.toml, or ssm-engine plugins (see --help)"
            ),
        },
    };
    let mut scene = SceneFile::load(&scene_path)?;
    if report && scene.scene.report.is_none() {
        scene.scene.report = Some(ReportSection { orders: None });
    }
    // every value checked before anything is written
    ssm_engine::plan::of_scene(&scene)?;
    let out = out.unwrap_or_else(|| job::default_out_dir(&scene));
    // before anything is computed or written: the results must not replace
    // an input of the run
    let mut inputs = scene_inputs(&scene, &mut registry);
    inputs.extend(resume.clone().flatten());
    check_not_input(&out, &inputs)?;
    let name = scene.name();
    let checkpoint = match &resume {
        None => {
            let stopped = Checkpoint::default_path(&out);
            if stopped.exists() {
                eprintln!(
                    "note: {} keeps a stopped run's full-system reference; this run starts over (--resume goes on from it)",
                    stopped.display()
                );
            }
            Checkpoint::fresh(&out, &name, &scene.text)
        }
        Some(None) => Checkpoint::resume(&Checkpoint::default_path(&out), &name, &scene.text)?,
        Some(Some(p)) => Checkpoint::resume(p, &name, &scene.text)?,
    };
    let progress = Display {
        spinner: spinner(),
        journal: Journal::beside(&out),
        checkpoint,
    };
    let result = job::run(&scene, &mut registry, &progress);
    progress.spinner.finish();
    let journal = if resume.is_some() {
        progress.journal.settle_resumed()
    } else {
        progress.journal.written()
    };
    let kept = progress.checkpoint.written();
    let stopped = |e: anyhow::Error| {
        if let Some(p) = &journal {
            eprintln!(
                "note: the full-system reference's orbits computed before the stop are in {}",
                p.display()
            );
        }
        if let Some(p) = &kept {
            eprintln!(
                "note: its continuation is kept in {}; `ssm-engine {}{} --out {} {}` goes on from there",
                p.display(),
                if report { "report " } else { "" },
                scene_path.display(),
                out.display(),
                if *p == Checkpoint::default_path(&out) {
                    "--resume".to_owned()
                } else {
                    format!("--resume-from {}", p.display())
                }
            );
        }
        e
    };
    if let (Some(p), n @ 1..) = (&kept, progress.checkpoint.restored()) {
        eprintln!(
            "note: {n} continuation run(s) of the reference restored from {}",
            p.display()
        );
    }
    let result = result.map_err(|e| stopped(e.into()))?;
    result.outputs.write(&out).map_err(|e| stopped(e.into()))?;
    // the run's own journal and checkpoint; a resumed run's outputs also
    // supersede the stopped run's journal
    let mut done: Vec<PathBuf> = journal.into_iter().chain(kept).collect();
    if resume.is_some() {
        done.extend(progress.journal.default_path());
    }
    for p in done {
        let _ = std::fs::remove_file(p);
    }
    for w in &result.warnings {
        eprintln!("warning: {w}");
    }
    match &result.spectrum {
        Some(spectrum) => println!(
            "{}: {} states, {} finite eigenvalues ({}), master pairs {:?}; wrote {}",
            scene.name(),
            result.system.n_states(),
            spectrum.eigenvalues.len(),
            spectrum.method.as_str(),
            scene.scene.ssm.master_pairs.get_ref(),
            out.display()
        ),
        None => println!(
            "{}: {} states, POD study of {} reduced model(s) on {} load(s); wrote {}",
            scene.name(),
            result.system.n_states(),
            result.pod.as_ref().map_or(0, |p| p.pod.len() + p.ssm.len()),
            result.pod.as_ref().map_or(0, |p| p.cases.len()),
            out.display()
        ),
    }
    Ok(())
}

/// `ssm-engine study`: a shard of a study's points (all by default), or
/// the merge of its store.
fn run_study(
    path: &std::path::Path,
    store: &std::path::Path,
    shard: Option<&str>,
    merge: bool,
    registry: &mut Registry,
) -> anyhow::Result<()> {
    let study = StudyFile::load(path)?;
    if merge {
        let (table, failed) = study::merge(&study, store)?;
        println!(
            "merged {} points ({failed} failed) into {}",
            study.points.values.len(),
            table.display()
        );
        return Ok(());
    }
    let shard = shard.map(study::parse_shard).transpose()?.unwrap_or((1, 1));
    let spinner = spinner();
    let started = std::time::Instant::now();
    let mut finished = 0usize;
    let mut note = |index: usize, record: &study::store::Record| {
        finished += 1;
        let error = record.iter().find_map(|(n, c)| match (n.as_str(), c) {
            ("error", study::store::Cell::Text(e)) => Some(e.clone()),
            _ => None,
        });
        let line = match error {
            Some(e) => format!("point {index}: failed: {e}"),
            None => format!("point {index}: done"),
        };
        spinner.stage(&format!(
            "{line} ({finished} this run, {:.1} s)",
            started.elapsed().as_secs_f64()
        ));
    };
    let report = study::run_shard(
        &study,
        store,
        shard,
        registry,
        &ssm_engine::progress::Quiet,
        &mut note,
    );
    spinner.finish();
    let report = report?;
    println!(
        "{}: shard {}/{}: {} points, {} computed ({} failed), {} already in {}",
        study.path.display(),
        shard.0,
        shard.1,
        report.points,
        report.computed,
        report.failed,
        report.skipped,
        store.display()
    );
    Ok(())
}

fn main() -> ExitCode {
    // A write beyond the file-size limit (`ulimit -f`, a quota) fails with
    // EFBIG, reported as a typed output error, instead of killing the
    // process with SIGXFSZ half-way through a result set.
    // SAFETY: setting a signal's disposition to SIG_IGN at start-up, before
    // any thread exists, has no handler that could race.
    unsafe {
        libc::signal(libc::SIGXFSZ, libc::SIG_IGN);
    }
    // freed factors are reused, not faulted in afresh (see the function)
    ssm_kernel::heap::retain_freed_memory();
    let cli = Cli::parse();
    match run(cli) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            // the chain of causes, each once (typed errors already quote their source)
            let mut msg = e.to_string();
            for cause in e.chain().skip(1) {
                let c = cause.to_string();
                if !msg.contains(&c) {
                    msg.push_str(": ");
                    msg.push_str(&c);
                }
            }
            eprintln!("error: {msg}");
            ExitCode::FAILURE
        }
    }
}
