//! The render threads: each slot waits for a new job, builds the edited
//! scene through the scene parser and builder, and renders it with the
//! progressive passes of `niebla::progressive` (1, 1, 2, 4, ... samples per
//! pixel), publishing the mean image after every pass. An edit cancels the
//! running pass (`RenderOptions`' cancel flag) and starts over.
//!
//! Each slot keeps the scene it built last and its integrator's
//! precomputation ([`SlotCache`]): an edit of the camera, of `render` or of
//! a medium's scalars (coefficients, density scale, phase, emission scale)
//! is applied to them (`niebla::scene::rebuild_scene`,
//! `PreparedIntegrator::update`) instead of loading grids and running the
//! precomputation again, with the same image as a fresh build. With
//! `NIEBLA_VIEW_TIMING` set, each job prints where its time went to stderr.

use std::sync::atomic::Ordering;
use std::sync::Arc;
use std::time::Instant;

use niebla::film::Image;
use niebla::integrator::IntegratorSettings;
use niebla::progressive::{resume_progressive_sums_prepared, Accumulator, Budget, ProgressiveOptions};
use niebla::render::{PreparedIntegrator, RenderError};
use niebla::scene::{build_scene, parse_scene_str, rebuild_scene, BuiltScene, CameraDesc, SceneDesc};
use serde_json::Value;

use crate::frame::{relative_error_estimate, Frame, FrameTiming};
use crate::session::{Job, Session, SlotInput};

/// What a slot keeps between jobs: the description it built last (camera
/// size as rendered), the built scene and the integrator prepared for it.
pub struct SlotCache {
    desc: SceneDesc,
    built: BuiltScene,
    prepared: Option<(IntegratorSettings, PreparedIntegrator)>,
}

/// The scene slot `index` renders for `job`: the edited scene itself (slot
/// 0), or with `render.integrator` replaced by the comparison integrator
/// (slot 1; `None` without a split view).
pub fn slot_scene(job: &Job, index: usize) -> Option<Value> {
    if index == 0 {
        return Some((*job.scene).clone());
    }
    let compare = job.compare.as_ref()?;
    Some(with_integrator(&job.scene, compare))
}

/// `scene` with `render.integrator` set to `integrator`.
pub fn with_integrator(scene: &Value, integrator: &Value) -> Value {
    let mut scene = scene.clone();
    if let Some(root) = scene.as_object_mut() {
        let render = root.entry("render").or_insert_with(|| Value::Object(Default::default()));
        if let Some(render) = render.as_object_mut() {
            render.insert("integrator".into(), integrator.clone());
        }
    }
    scene
}

/// Run render slot `index` until the session stops. A new job whose input
/// for this slot equals that of the last render, finished or still valid,
/// is skipped (its frames stand).
pub fn run_slot(session: Arc<Session>, index: usize) {
    let mut seen = 0;
    let mut done: Option<SlotInput> = None;
    let mut cache: Option<SlotCache> = None;
    let timing = std::env::var_os("NIEBLA_VIEW_TIMING").is_some();
    // With `--threads`, one pool for the slot's whole life: building one per
    // pass (as `RenderOptions::threads` does) costs a thread start-up per frame.
    let pool = match session.threads {
        Some(threads) => match rayon::ThreadPoolBuilder::new().num_threads(threads).build() {
            Ok(pool) => Some(pool),
            Err(e) => {
                slot_error(&session, index, format!("cannot start {threads} render threads: {e}"));
                return;
            }
        },
        None => None,
    };
    while let Some(job) = session.wait_job(seen) {
        seen = job.version;
        let slot = &session.slots[index];
        let input = job.slot_input(index);
        if done.as_ref() == Some(&input) && !slot.cancel.load(Ordering::SeqCst) {
            continue;
        }
        slot.cancel.store(false, Ordering::SeqCst);
        if session.job().slot_input(index) != input {
            continue; // an edit came between taking the job and clearing the flag
        }
        done = None;
        let Some(scene) = &input.scene else { continue };
        slot.rendering_interactive.store(job.interactive, Ordering::SeqCst);
        let mut run = || render_job(&session, index, &job, scene, &mut cache, timing);
        let result = match &pool {
            Some(pool) => pool.install(run),
            None => run(),
        };
        slot.rendering_interactive.store(false, Ordering::SeqCst);
        match result {
            Ok(()) if !slot.cancel.load(Ordering::SeqCst) => done = Some(input),
            Ok(()) => {}
            Err(message) => slot.publish_error(job.version, message),
        }
    }
}

/// Report `message` as slot `index`'s error for the current job.
fn slot_error(session: &Session, index: usize, message: String) {
    session.slots[index].publish_error(session.job().version, message);
}

/// The scene of `desc` ready to render: `cache`'s scene brought up to
/// date when the edit allows (`rebuild_scene`), else built anew; the
/// prepared integrator updated or made. Returns how the scene was obtained
/// (for the timing line).
fn prepare(
    session: &Session,
    desc: SceneDesc,
    cache: &mut Option<SlotCache>,
    cancel: &std::sync::atomic::AtomicBool,
    interactive: bool,
) -> Result<(&'static str, &'static str), String> {
    let rebuilt = cache
        .as_ref()
        .and_then(|c| rebuild_scene(&c.built, &c.desc, &desc, &session.label, &session.base).map(|r| (r, c)));
    let (built, edit, how) = match rebuilt {
        Some((Ok((built, edit)), _)) => {
            let how = match (edit.any_light(), edit.any_medium()) {
                (true, _) => "lights",
                (false, true) => "media",
                (false, false) => "camera",
            };
            (built, Some(edit), how)
        }
        Some((Err(e), _)) => return Err(e.to_string()),
        None => {
            *cache = None; // free the old grids before loading the new ones
            (build_scene(&desc, &session.label, &session.base).map_err(|e| e.to_string())?, None, "built")
        }
    };
    let settings = built.settings.integrator;
    let old = cache.take().and_then(|c| c.prepared);
    let (prepared, kept) = match (old, edit) {
        (Some((old_settings, mut prepared)), Some(edit)) if old_settings == settings => {
            // A drag frame may take `zhou`'s coarser preview lighting and
            // `zhou`'s and `hegeman`'s coarser march step; the next
            // non-interactive job lights on the full lattice and marches
            // the exact step again.
            let done = match interactive {
                true => prepared.update_preview_cancellable(&built.scene, &settings, &edit, Some(cancel)),
                false => prepared.update_cancellable(&built.scene, &settings, &edit, Some(cancel)),
            };
            if !done {
                // A newer edit stopped it: drop the half-updated integrator.
                *cache = Some(SlotCache { desc, built, prepared: None });
                return Ok((how, "cancelled"));
            }
            let kept = if prepared.is_preview() { "updated (preview)" } else { "updated" };
            (prepared, kept)
        }
        _ => {
            if cancel.load(Ordering::SeqCst) {
                // A newer edit came: leave the slow precomputation to it.
                *cache = Some(SlotCache { desc, built, prepared: None });
                return Ok((how, "skipped"));
            }
            match PreparedIntegrator::new_cancellable(&built.scene, &settings, cancel) {
                // A drag frame marches the coarser drag step (hegeman, zhou);
                // the next non-interactive job's update restores the exact one.
                Some(mut prepared) if interactive => {
                    prepared.set_drag_march(true);
                    (prepared, "new (preview)")
                }
                Some(prepared) => (prepared, "new"),
                None => {
                    *cache = Some(SlotCache { desc, built, prepared: None });
                    return Ok((how, "cancelled"));
                }
            }
        }
    };
    *cache = Some(SlotCache { desc, built, prepared: Some((settings, prepared)) });
    Ok((how, kept))
}

/// Build and render one job in slot `index`, publishing every pass; an
/// error message when the scene does not build (a cancelled render is no
/// error).
fn render_job(
    session: &Session,
    index: usize,
    job: &Job,
    scene: &Value,
    cache: &mut Option<SlotCache>,
    timing: bool,
) -> Result<(), String> {
    let start = Instant::now();
    let queue = job.edited_at.map_or(0.0, |t| start.duration_since(t).as_secs_f64() - job.validate_seconds);
    let text = serde_json::to_string(scene).map_err(|e| e.to_string())?;
    let mut desc = parse_scene_str(&text, &session.label).map_err(|e| e.to_string())?;
    if job.interactive {
        let divisor = job.preview_scale.clamp(1, 16);
        let CameraDesc::Perspective(camera) = &mut desc.camera;
        camera.width = camera.width.div_ceil(divisor).max(1);
        camera.height = camera.height.div_ceil(divisor).max(1);
    }
    let parsed = start.elapsed();
    let slot = &session.slots[index];
    let (how, kept) = prepare(session, desc, cache, &slot.cancel, job.interactive)?;
    let prepared_at = start.elapsed();
    let Some(SlotCache { built, prepared: Some((_, prepared)), .. }) = cache.as_ref() else {
        return Ok(()); // cancelled before the precomputation
    };
    let settings = built.settings;
    let world = &built.scene;
    let budget = Budget::Samples(if job.interactive { 1 } else { job.max_spp.max(1) });
    let options = ProgressiveOptions {
        threads: None, // the slot's pool (`run_slot`) or the global one
        sampler: settings.sampler,
        cancel: Some(&slot.cancel),
        ..ProgressiveOptions::new(&settings.integrator, settings.seed, budget)
    };
    let (width, height) = (world.camera.width, world.camera.height);
    let mut previous: Option<Image> = None;
    let mut first = true;
    let accumulator = Accumulator::new(width, height);
    let mut pass_start = Instant::now();
    let result = resume_progressive_sums_prepared(world, prepared, &options, accumulator, |acc, info| {
        let pass = pass_start.elapsed().as_secs_f64();
        let image_start = Instant::now();
        if timing && first {
            eprintln!(
                "niebla view: slot {index} version {} ({}x{}{}): parse {:.1} ms, scene {how} + integrator {kept} \
                 {:.1} ms, first pass {:.1} ms",
                job.version,
                width,
                height,
                if job.interactive { ", interactive" } else { "" },
                parsed.as_secs_f64() * 1e3,
                (prepared_at - parsed).as_secs_f64() * 1e3,
                (start.elapsed() - prepared_at).as_secs_f64() * 1e3,
            );
        }
        let image = acc.image();
        let relative_error = previous.as_ref().and_then(|p| relative_error_estimate(p, &image));
        let elapsed = start.elapsed().as_secs_f64();
        let samples = acc.spp as f64 * width as f64 * height as f64;
        let stage = |s: f64| if first { s } else { 0.0 };
        let timing = FrameTiming {
            edited_at: job.edited_at.filter(|_| first),
            validate: stage(job.validate_seconds),
            queue: stage(queue),
            parse: stage(parsed.as_secs_f64()),
            prepare: stage((prepared_at - parsed).as_secs_f64()),
            pass,
            image: image_start.elapsed().as_secs_f64(),
            published: Instant::now(),
        };
        first = false;
        slot.publish_frame(Frame {
            id: 0,
            version: job.version,
            width,
            height,
            spp: info.spp,
            elapsed,
            samples_per_second: samples / info.elapsed.as_secs_f64().max(1e-9),
            relative_error,
            interactive: job.interactive,
            integrator: settings.integrator.name().to_string(),
            image: Arc::new(image.clone()),
            timing,
        });
        previous = Some(image);
        pass_start = Instant::now();
        !slot.cancel.load(Ordering::SeqCst)
    });
    match result {
        Ok(_) | Err(RenderError::Cancelled) => Ok(()),
        Err(e) => Err(e.to_string()),
    }
}
