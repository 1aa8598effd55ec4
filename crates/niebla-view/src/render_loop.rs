//! The render threads: each slot waits for a new job, builds the edited
//! scene through the scene parser and builder, and renders it with the
//! progressive passes of `niebla::progressive` (1, 1, 2, 4, ... samples per
//! pixel), publishing the mean image after every pass. An edit cancels the
//! running pass (`RenderOptions`' cancel flag) and starts over.

use std::sync::atomic::Ordering;
use std::sync::Arc;
use std::time::Instant;

use niebla::film::Image;
use niebla::progressive::{resume_progressive_sums, Accumulator, Budget, ProgressiveOptions};
use niebla::render::RenderError;
use niebla::scene::{build_scene, parse_scene_str};
use serde_json::Value;

use crate::frame::{relative_error_estimate, Frame};
use crate::session::{Job, Session, SlotInput};

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
        let result = render_job(&session, index, &job, scene);
        slot.rendering_interactive.store(false, Ordering::SeqCst);
        match result {
            Ok(()) if !slot.cancel.load(Ordering::SeqCst) => done = Some(input),
            Ok(()) => {}
            Err(message) => slot.publish_error(job.version, message),
        }
    }
}

/// Build and render one job in slot `index`, publishing every pass; an
/// error message when the scene does not build (a cancelled render is no
/// error).
fn render_job(session: &Session, index: usize, job: &Job, scene: &Value) -> Result<(), String> {
    let start = Instant::now();
    let text = serde_json::to_string(scene).map_err(|e| e.to_string())?;
    let desc = parse_scene_str(&text, &session.label).map_err(|e| e.to_string())?;
    let built = build_scene(&desc, &session.label, &session.base).map_err(|e| e.to_string())?;
    let settings = built.settings;
    let mut world = built.scene;
    if job.interactive {
        let divisor = job.preview_scale.clamp(1, 16);
        world.camera.width = world.camera.width.div_ceil(divisor).max(1);
        world.camera.height = world.camera.height.div_ceil(divisor).max(1);
    }
    let slot = &session.slots[index];
    let budget = Budget::Samples(if job.interactive { 1 } else { job.max_spp.max(1) });
    let options = ProgressiveOptions {
        threads: session.threads,
        sampler: settings.sampler,
        cancel: Some(&slot.cancel),
        ..ProgressiveOptions::new(&settings.integrator, settings.seed, budget)
    };
    let (width, height) = (world.camera.width, world.camera.height);
    let mut previous: Option<Image> = None;
    let result = resume_progressive_sums(&world, &options, Accumulator::new(width, height), |acc, info| {
        let image = acc.image();
        let relative_error = previous.as_ref().and_then(|p| relative_error_estimate(p, &image));
        let elapsed = start.elapsed().as_secs_f64();
        let samples = acc.spp as f64 * width as f64 * height as f64;
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
        });
        previous = Some(image);
        !slot.cancel.load(Ordering::SeqCst)
    });
    match result {
        Ok(_) | Err(RenderError::Cancelled) => Ok(()),
        Err(e) => Err(e.to_string()),
    }
}
