//! `niebla render`.

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::{Duration, Instant};

use clap::{Args, ValueEnum};
use indicatif::{ProgressBar, ProgressStyle};
use niebla::adaptive::StopRule;
use niebla::film::{read_checkpoint_full, render_memory, write_checkpoint, write_image, Checkpoint, CheckpointInfo};
use niebla::integrator::IntegratorSettings;
use niebla::progressive::{resume_progressive_sums, Accumulator, Budget, PassInfo, ProgressiveOptions};
use niebla::render::{recorded_key, split_recorded_key};
use niebla::sampling::SamplerKind;
use niebla::scene::IntegratorSpec;

use crate::error::CliError;
use crate::flags::{
    check_output_folder, positive_seconds, DefineFlag, ExposureFlag, MaxMemoryFlag, QuietFlag, SeedFlag, ThreadsFlag,
};

/// Options of `niebla render`.
#[derive(Args, Debug)]
pub struct RenderArgs {
    /// Scene file (JSON, version 1, or Mitsuba 3 XML with extension .xml).
    /// Without it, renders the built-in default scene: a hazy room with a
    /// spot light.
    pub scene: Option<PathBuf>,
    /// Output image: .exr (linear float32 radiance) or .png (exposure, sRGB,
    /// 8-bit). Only the named file is written. Default: both <scene>.exr and
    /// <scene>.png in the current folder.
    #[arg(short, long)]
    pub output: Option<PathBuf>,
    /// Image width in pixels (overrides the camera's `width`; the height
    /// keeps the camera's aspect, rounded to the nearest pixel, at least 1),
    /// as `niebla bench interactive --error-width` sizes its error images.
    /// The EXR header records the scene file's hash, not the size: --resume
    /// and `niebla merge` check the size themselves.
    #[arg(long, value_name = "PIXELS")]
    pub width: Option<u32>,
    /// Samples per pixel (overrides the scene's `render.spp`).
    #[arg(long, conflicts_with = "time")]
    pub spp: Option<u32>,
    /// Index of the first sample: render samples N .. N + spp of every
    /// pixel (one machine's share of a render; the EXR header records the
    /// range, and `niebla merge` adds disjoint ranges up to the image of one
    /// render of all of them, bit for bit).
    #[arg(long, value_name = "N", default_value_t = 0, conflicts_with = "resume")]
    pub first_sample: u64,
    /// Render for about this many seconds instead of a sample count: passes
    /// double the sample count while the next pass fits in the time left.
    #[arg(long)]
    pub time: Option<f64>,
    /// Largest number of scattering events per path (volpath; default 1024).
    #[arg(long)]
    pub max_depth: Option<u32>,
    /// Integrator (overrides the scene's `render.integrator.type`; its other
    /// parameters take defaults unless the scene names the same integrator).
    #[arg(long, value_parser = integrator_names())]
    pub integrator: Option<String>,
    /// Scattering-point sampling of the `single` integrator: march (ray
    /// marching), equiangular (toward point and spot lights) or mis
    /// (equiangular + distance sampling).
    #[arg(long, value_enum)]
    pub sampling: Option<SamplingName>,
    /// Numbers of the camera samples (overrides the scene's
    /// `render.sampler`): independent or sobol (Owen-scrambled Sobol points).
    #[arg(long, value_parser = clap::builder::PossibleValuesParser::new(niebla::sampling::SamplerKind::NAMES))]
    pub sampler: Option<String>,
    /// `--threads`: worker threads.
    #[command(flatten)]
    pub threads: ThreadsFlag,
    /// `--seed`: the sampler seed.
    #[command(flatten)]
    pub seed: SeedFlag,
    /// `--exposure`: exposure of the images, in stops.
    #[command(flatten)]
    pub exposure: ExposureFlag,
    /// `-D NAME=VALUE`: parameters of a Mitsuba XML scene.
    #[command(flatten)]
    pub define: DefineFlag,
    /// `--quiet`: no progress bars.
    #[command(flatten)]
    pub quiet: QuietFlag,
    /// `--max-memory`: the memory limit.
    #[command(flatten)]
    pub max_memory: MaxMemoryFlag,
    /// Continue the progressive render whose EXR checkpoint (an output of an
    /// earlier `niebla render`, rewritten between passes) is given, up to
    /// --spp samples in all: same scene, integrator, sampler and seed required, and
    /// the result is bit-identical to a render that was never stopped.
    #[arg(long, value_name = "CHECKPOINT.exr")]
    pub resume: Option<PathBuf>,
    /// Write the outputs once, at the end, not also as checkpoints between
    /// passes (at most a second apart otherwise): for benchmarks that time a
    /// render's CPU seconds without the image compression. A render stopped
    /// early then leaves no image.
    #[arg(long)]
    pub no_checkpoints: bool,
    /// Layers written beside the beauty, comma-separated (added to the
    /// scene's `film.aovs`): alpha, direct, indirect, emission, surface,
    /// albedo, normal, depth, variance, or all. EXR outputs hold them as
    /// channel groups (`A`, `direct.R`, ...); PNG outputs stay the beauty
    /// (RGBA with alpha).
    #[arg(long, value_name = "LIST")]
    pub aovs: Option<String>,
    /// Hold out the background (the scene's `film.transparent`): rays that
    /// see the environment directly see black, alpha is written, and the
    /// environment still lights the scene.
    #[arg(long)]
    pub transparent: bool,
    /// Also write a denoised image beside each output (`shot.exr` ->
    /// `shot.denoised.exr`), by Intel Open Image Denoise on the CPU guided by
    /// the albedo and normal layers (rendered for it). Needs the OIDN
    /// library: `pip install pyoidn` and NIEBLA_OIDN_LIBRARY (see README).
    #[arg(long)]
    pub denoise: bool,
    /// Adaptive sampling: a pixel stops taking samples once the predicted
    /// relative standard error of its value (from the first half of its
    /// samples) is below THRESHOLD, in (0, 1), and so is its neighbours';
    /// the image stays unbiased. --spp is the most a pixel takes. The EXR
    /// also holds `spp.Z` (samples per pixel), `variance.RGB` and the
    /// --aovs layers (each pixel's by the same rule as its beauty); it is not
    /// a checkpoint (no --resume). Uses the independent sampler (the
    /// argument needs independent passes; `--sampler sobol` is refused).
    #[arg(long, value_name = "THRESHOLD", conflicts_with_all = ["time", "resume", "denoise"])]
    pub adaptive: Option<f32>,
    /// With --adaptive: stop by cost instead of by error. A pixel stops
    /// once the relative variance the next pass would remove from its value,
    /// per unit of the pass's cost (random numbers its samples drew so far,
    /// plus a fixed part), is below THRESHOLD^2 / (spp x the image's mean cost
    /// per sample): the allocation of samples that minimises the image's
    /// relative MSE for the time spent. About: a pixel stops after n samples
    /// once its predicted relative error is below
    /// THRESHOLD x sqrt((n / spp) (cost / mean cost)). Still unbiased.
    #[arg(long, requires = "adaptive")]
    pub adaptive_cost: bool,
    /// Samples allocated by an independent pilot: a pilot render of
    /// --pilot-spp samples per pixel (its own random stream) estimates each
    /// pixel's relative variance v and cost c per sample (random numbers
    /// drawn, counted), both averaged over the 5x5 neighbourhood; then each
    /// pixel takes n ~ sqrt(v / c) samples (the least time for a relative
    /// MSE), between spp / 8 (at least 1) and 8 spp, --spp on average. The
    /// value is the mean of those n samples only (the pilot's are
    /// discarded), so the image is unbiased with any --sampler, sobol
    /// included. The EXR also holds `spp.Z`, `variance.RGB` and the --aovs
    /// layers; not a checkpoint (no --resume).
    #[arg(long, conflicts_with_all = ["time", "resume", "denoise", "adaptive"])]
    pub adaptive_pilot: bool,
    /// With --adaptive-pilot: samples per pixel of the pilot (at least 2;
    /// they come on top of --spp).
    #[arg(long, value_name = "N", requires = "adaptive_pilot", default_value_t = niebla::adaptive::pilot::DEFAULT_PILOT_SPP)]
    pub pilot_spp: u32,
    /// Render frames of a sequence: `N`, `FIRST-LAST` or `FIRST-LAST:STEP`
    /// (frame numbers >= 0). Frame patterns in the scene's file names
    /// (`smoke.####.vdb`, `{frame}`, `{frame:04}`) and keyframes of the
    /// camera and lights take each frame's values; -o must name the outputs
    /// with a frame pattern (`-o out.####.exr`). Every frame's files are
    /// checked before the first renders; frames whose output exists are
    /// skipped (see --overwrite); --time is a budget per frame.
    #[arg(long, value_name = "RANGE", conflicts_with = "resume")]
    pub frames: Option<String>,
    /// With --frames: render frames whose output already exists again
    /// (default: skip them; an output exists only once its frame is finished).
    #[arg(long, requires = "frames")]
    pub overwrite: bool,
}

/// Scattering-point sampling of `single`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum SamplingName {
    /// Stratified ray marching.
    March,
    /// Equiangular sampling toward point and spot lights.
    Equiangular,
    /// Equiangular and distance sampling combined by MIS.
    Mis,
}

/// The `--integrator` values: every name of the integrator registry, with
/// its summary in `--help`.
pub fn integrator_names() -> clap::builder::PossibleValuesParser {
    clap::builder::PossibleValuesParser::new(
        niebla::integrator::registry::INTEGRATORS
            .iter()
            .map(|e| clap::builder::PossibleValue::new(e.name).help(e.summary)),
    )
}

impl SamplingName {
    /// The value of the `sampling` field in a scene file.
    fn field(self) -> &'static str {
        match self {
            SamplingName::March => "march",
            SamplingName::Equiangular => "equiangular",
            SamplingName::Mis => "mis",
        }
    }
}

/// The scene's integrator (`spec`) with the command-line overrides applied,
/// read by the integrator registry: `--integrator` naming another
/// integrator takes that one's defaults; `--sampling` (single) and
/// `--max-depth` (volpath) set that field.
pub fn override_integrator(
    spec: &IntegratorSpec,
    name: Option<&str>,
    sampling: Option<SamplingName>,
    max_depth: Option<u32>,
) -> Result<IntegratorSettings, CliError> {
    let kind = name.unwrap_or(spec.name());
    let mut fields = Vec::new();
    if let Some(choice) = sampling {
        if kind != "single" {
            return Err(CliError::Integrator(format!("--sampling applies to the single integrator, not to {kind}")));
        }
        fields.push(("sampling", serde_json::Value::from(choice.field())));
    }
    if let Some(depth) = max_depth {
        if kind != "volpath" {
            return Err(CliError::Integrator(format!("--max-depth applies to the volpath integrator, not to {kind}")));
        }
        fields.push(("max_depth", serde_json::Value::from(depth)));
    }
    niebla::integrator::registry::parse_with_overrides(&spec.object, name, &fields).map_err(|e| {
        let option = if e.path == "max_depth" { "--max-depth" } else { "--integrator" };
        CliError::Integrator(format!("{option}: render.integrator.{}: {}", e.path, e.message))
    })
}

/// `niebla render`.
pub fn run(args: &RenderArgs) -> Result<(), CliError> {
    if let Some(range) = &args.frames {
        return crate::render_frames::run(args, range);
    }
    if let Some(note) = args.scene.as_deref().and_then(still_render_note) {
        eprintln!("note: {note}");
    }
    let loaded =
        crate::load::load_limited_defined(args.scene.as_deref(), args.max_memory.limit(), &args.define.define)?;
    for note in &loaded.notes {
        eprintln!("note: {note}");
    }
    let outputs = output_paths(args.output.as_deref(), &loaded.stem)?;
    let bar = if args.quiet.quiet { ProgressBar::hidden() } else { ProgressBar::new(1) };
    if let Some(line) = render_loaded(args, loaded, &outputs, bar, !args.no_checkpoints)? {
        println!("{line}");
    }
    Ok(())
}

/// For a scene file that changes with the frame (frame patterns in file
/// names, keyframes) rendered without `--frames`: a note saying that it is
/// rendered as written.
fn still_render_note(scene: &Path) -> Option<String> {
    let text = std::fs::read_to_string(scene).ok()?;
    let value: serde_json::Value = serde_json::from_str(&text).ok()?;
    let animated = niebla::scene::frames::animated_fields(&value);
    if animated.is_empty() {
        return None;
    }
    Some(format!(
        "{}: {} change with the frame; without --frames the scene is rendered as written (file names literal, \
         keyframes not applied); --frames N renders frame N",
        scene.display(),
        animated.join(", ")
    ))
}

/// The output files: `output` if given (an .exr or .png), else
/// `<stem>.exr` and `<stem>.png`; their folders must exist.
pub fn output_paths(output: Option<&Path>, stem: &str) -> Result<Vec<PathBuf>, CliError> {
    let outputs: Vec<PathBuf> = match output {
        Some(p) => {
            let ext = p.extension().and_then(|e| e.to_str()).map(|e| e.to_ascii_lowercase());
            if !matches!(ext.as_deref(), Some("exr") | Some("png")) {
                return Err(CliError::OutputFormat(p.to_path_buf()));
            }
            vec![p.to_path_buf()]
        }
        None => vec![PathBuf::from(format!("{stem}.exr")), PathBuf::from(format!("{stem}.png"))],
    };
    for out in &outputs {
        check_output_folder(out)?;
    }
    Ok(outputs)
}

/// Renders a loaded scene to `outputs` as the options ask, drawing progress
/// on `bar` (cleared at the end); with `checkpoints`, the outputs are also
/// written between passes (at most [`CHECKPOINT_INTERVAL`] apart). Returns
/// the line that reports the render (`None` where the adaptive render
/// printed its own).
pub fn render_loaded(
    args: &RenderArgs,
    loaded: crate::load::LoadedScene,
    outputs: &[PathBuf],
    bar: ProgressBar,
    checkpoints: bool,
) -> Result<Option<String>, CliError> {
    let max_memory = args.max_memory.limit();
    let crate::load::LoadedScene { mut built, hash, .. } = loaded;
    if let Some(width) = args.width {
        if !(1..=16384).contains(&width) {
            return Err(CliError::invalid_option("--width", "must be between 1 and 16384"));
        }
        built.scene.camera = resized_camera(&built.scene.camera, width);
    }
    let integrator =
        override_integrator(&built.integrator_spec, args.integrator.as_deref(), args.sampling, args.max_depth)?;
    let denoiser = crate::aov_flags::denoiser(args.denoise)?;
    let aovs = crate::aov_flags::layers(&mut built, args.aovs.as_deref(), args.transparent, &integrator)?;
    let aovs = crate::aov_flags::with_denoise_features(aovs, denoiser.is_some(), &integrator)?;
    let (width, height) = (built.scene.camera.width, built.scene.camera.height);
    let left = max_memory
        .saturating_sub(render_memory(width, height))
        .saturating_sub(niebla::aov::aov_memory(width, height, aovs));
    crate::load::check_precompute_memory(
        &crate::load::scene_label(args.scene.as_deref()),
        &integrator,
        &built.scene,
        left,
    )?;
    let spp = args.spp.unwrap_or(built.settings.spp);
    if spp == 0 {
        return Err(CliError::invalid_option("--spp", "must be at least 1"));
    }
    let budget = match args.time {
        Some(t) => Budget::Time(Duration::from_secs_f64(positive_seconds("--time", t)?)),
        None => Budget::Samples(spp),
    };
    let threads = args.threads.get()?;
    let exposure = args.exposure.or(built.settings.exposure)?;
    let scene = &built.scene;
    let transparent = scene.transparent_background;
    let pixels = scene.camera.width as u64 * scene.camera.height as u64;
    let sampler = args.sampler.as_deref().and_then(SamplerKind::parse).unwrap_or(built.settings.sampler);
    if args.adaptive_pilot {
        let mut options = niebla::adaptive::pilot::PilotOptions::new(spp, args.seed.or(built.settings.seed), sampler);
        options.pilot_spp = args.pilot_spp;
        options.threads = threads;
        options.layers = aovs;
        let run = crate::adaptive_cmd::PilotRun { options, exposure, quiet: args.quiet.quiet };
        return crate::adaptive_cmd::run_pilot(scene, &integrator, &run, args.first_sample, outputs).map(|()| None);
    }
    if let Some(threshold) = args.adaptive {
        if args.sampler.as_deref().and_then(SamplerKind::parse) == Some(SamplerKind::Sobol) {
            return Err(CliError::invalid_option(
                "--adaptive",
                "renders with the independent sampler (its unbiasedness needs passes independent of each other, \
                 which Sobol points are not); drop --sampler sobol",
            ));
        }
        let seed = args.seed.or(built.settings.seed);
        let quiet = args.quiet.quiet;
        let rule = if args.adaptive_cost { StopRule::Cost } else { StopRule::Error };
        let run =
            crate::adaptive_cmd::AdaptiveRun { threshold, spp, seed, threads, exposure, quiet, layers: aovs, rule };
        return crate::adaptive_cmd::run(scene, &integrator, &run, args.first_sample, outputs).map(|()| None);
    }
    let (start_acc, seed) = match &args.resume {
        None => (
            Accumulator::starting_at(scene.camera.width, scene.camera.height, args.first_sample),
            args.seed.or(built.settings.seed),
        ),
        Some(path) => {
            let (acc, seed) = resume_state(path, scene, &hash, (&integrator, sampler), args.seed.seed)?;
            (crate::aov_flags::resume_layers(path, acc, aovs, transparent)?, seed)
        }
    };
    if let (Some(path), Budget::Samples(target)) = (&args.resume, budget) {
        if start_acc.spp >= u64::from(target) {
            let line =
                format!("{}: already has {} spp (>= --spp {target}); nothing to render", path.display(), start_acc.spp);
            return Ok(Some(line));
        }
    }
    let template = match budget {
        Budget::Samples(_) => {
            bar.set_length(pixels * spp as u64);
            "{spinner} [{elapsed_precise}] {wide_bar} {percent:>3}% {human_pos}/{human_len} samples, {per_sec}, ETA {eta} {msg}"
        }
        Budget::Time(t) => {
            bar.set_length((t.as_secs_f64() * 1000.0) as u64);
            "{spinner} [{elapsed_precise}] {wide_bar} {percent:>3}% of the time budget {msg}"
        }
    };
    bar.set_style(ProgressStyle::with_template(template).expect("the progress bar templates are valid"));
    let start = Instant::now();
    let samples_before_pass = AtomicU64::new(start_acc.spp * pixels);
    let progress = |done: u64, _total: u64| match budget {
        Budget::Samples(_) => bar.set_position(samples_before_pass.load(Ordering::Relaxed) + done),
        Budget::Time(_) => bar.set_position(start.elapsed().as_millis() as u64),
    };
    // After a pass, checkpoint the outputs (each written to a temporary file
    // and renamed), so a long render stopped at any time leaves a usable
    // image. EXR outputs are checkpoints: their header records the samples so
    // far, the seed, the scene's hash and the integrator and sampler, for --resume.
    // Checkpoints are at most CHECKPOINT_INTERVAL apart: the first passes take
    // milliseconds, and compressing and writing an image after each of them
    // took up to a third of a short render. The final image is always written.
    let mut write_error: Option<CliError> = None;
    let mut spp_done = start_acc.spp;
    let mut spp_written = start_acc.spp;
    let mut last_write = Instant::now();
    let write_outputs = |acc: &Accumulator| -> Result<(), CliError> {
        let checkpoint = CheckpointInfo {
            spp: acc.spp,
            seed,
            scene_hash: hash.clone(),
            integrator: recorded_key(&integrator, sampler),
            ranges: vec![(acc.first_sample, acc.next_sample())],
        };
        for out in outputs {
            let is_exr = out.extension().is_some_and(|e| e.eq_ignore_ascii_case("exr"));
            if let Some(layers) = acc.aov_sums() {
                niebla::aov::write_aov_outputs(acc.sums(), layers, &checkpoint, transparent, out, exposure)
            } else if is_exr {
                write_checkpoint(acc.sums(), &checkpoint, out)
            } else {
                write_image(&acc.image(), out, exposure)
            }?;
        }
        Ok(())
    };
    let on_pass = |acc: &Accumulator, info: PassInfo| {
        samples_before_pass.store(info.spp * pixels, Ordering::Relaxed);
        spp_done = info.spp;
        bar.set_message(format!("({} spp)", info.spp));
        if !checkpoints || last_write.elapsed() < CHECKPOINT_INTERVAL {
            return true;
        }
        if let Err(e) = write_outputs(acc) {
            write_error = Some(e);
            return false;
        }
        spp_written = info.spp;
        last_write = Instant::now();
        true
    };
    let options = ProgressiveOptions {
        threads,
        sampler,
        progress: &progress,
        aovs,
        ..ProgressiveOptions::new(&integrator, seed, budget)
    };
    let acc = resume_progressive_sums(scene, &options, start_acc, on_pass)?;
    // Rendering time, checkpoints included; the final write is not (as a
    // renderer's own timing of a render excludes saving the result).
    let seconds = start.elapsed().as_secs_f64();
    // The process's CPU seconds so far (loading included, the final write
    // not): what a benchmark compares with a peer's render-call CPU time.
    let cpu_seconds = crate::bench_photons_time::process_cpu_seconds().ok();
    if let Some(e) = write_error {
        bar.finish_and_clear();
        return Err(e);
    }
    if spp_written != spp_done {
        write_outputs(&acc)?;
    }
    if let Some(denoiser) = &denoiser {
        crate::aov_flags::write_denoised(denoiser, &acc, outputs, exposure)?;
    }
    bar.finish_and_clear();
    let names: Vec<String> = outputs.iter().map(|p| p.display().to_string()).collect();
    Ok(Some(format!(
        "rendered {}x{} at {} spp with {} in {:.2} s{} ({:.2} M samples/s) -> {}",
        scene.camera.width,
        scene.camera.height,
        spp_done,
        integrator.name(),
        seconds,
        cpu_seconds.map_or(String::new(), |c| format!(", process CPU {c:.3} s before the final write")),
        (pixels * spp_done) as f64 / seconds / 1e6,
        names.join(", ")
    )))
}

/// `camera` at `width` pixels wide, its height keeping the aspect ratio
/// (rounded to the nearest pixel, at least 1): the size convention of
/// `niebla bench interactive`'s error images and of `render --width`.
pub fn resized_camera(camera: &niebla::camera::PerspectiveCamera, width: u32) -> niebla::camera::PerspectiveCamera {
    let aspect = camera.height as f64 / camera.width as f64;
    let mut c = *camera;
    c.width = width;
    c.height = ((width as f64 * aspect).round() as u32).max(1);
    c
}

/// Least time between two checkpoints written during a render.
const CHECKPOINT_INTERVAL: std::time::Duration = std::time::Duration::from_secs(1);

/// The accumulator and seed to continue the checkpoint at `path` with,
/// after checking that it was rendered from this scene text, with these
/// integrator settings and sampler, at this image size (and with `seed` if one
/// is given).
fn resume_state(
    path: &Path,
    scene: &niebla::scene::Scene,
    hash: &str,
    (integrator, sampler): (&IntegratorSettings, SamplerKind),
    seed: Option<u64>,
) -> Result<(Accumulator, u64), CliError> {
    let Checkpoint { image, info, sums } = read_checkpoint_full(path).map_err(CliError::CheckpointUnreadable)?;
    let mismatch = |problem: String| CliError::CheckpointMismatch { path: path.to_path_buf(), problem };
    if info.scene_hash != hash {
        return Err(mismatch(format!(
            "was rendered from another scene (scene hash {}, this scene's {hash})",
            info.scene_hash
        )));
    }
    // Checkpoints name the settings by their stable key; those written
    // before it by the settings' Rust debug form, which is still accepted.
    let settings = integrator.key();
    let (recorded, recorded_sampler) = split_recorded_key(&info.integrator);
    if recorded != settings && recorded != format!("{integrator:?}") {
        return Err(mismatch(format!("was rendered with {recorded}, not {settings}")));
    }
    if recorded_sampler != Some(sampler) {
        let name = recorded_sampler.map_or(info.integrator.as_str(), |s| s.name());
        return Err(mismatch(format!("was rendered with the {name} sampler, not {}", sampler.name())));
    }
    if let Some(s) = seed.filter(|&s| s != info.seed) {
        return Err(mismatch(format!("was rendered with seed {}, not --seed {s}", info.seed)));
    }
    let (w, h) = (scene.camera.width, scene.camera.height);
    if (image.width, image.height) != (w, h) {
        return Err(mismatch(format!("is {} x {} pixels, the scene's camera {w} x {h}", image.width, image.height)));
    }
    if info.spp == 0 || image.pixels.iter().any(|p| !p.is_finite()) {
        return Err(mismatch("holds no samples or non-finite pixels; start a new render".to_string()));
    }
    let acc = match (info.ranges.as_slice(), sums) {
        (&[(first, _)], Some(sums)) => Accumulator::from_sums(sums, first, info.spp),
        // Checkpoints of version 1 store the mean of samples 0 .. spp alone.
        (&[(0, _)], None) => Accumulator::from_mean(image, info.spp),
        _ => {
            let ranges = CheckpointInfo::ranges_text(&info.ranges);
            return Err(mismatch(format!(
                "holds the sample ranges {ranges}; only a render of one range of samples can be continued"
            )));
        }
    };
    Ok((acc, info.seed))
}
