//! Rendering from Python: the renderer's progressive render on a worker
//! thread, the calling thread waiting with the GIL released.
//!
//! Why a worker thread: Python runs signal handlers (Ctrl-C) only on the
//! main thread and only when that thread holds the GIL, and progress bars
//! (tqdm, notebooks) want to be updated from the thread that owns them. So
//! the caller waits on the worker's result in slices of 50 ms with the GIL
//! released (`py.allow_threads`); between slices it takes the GIL back,
//! runs `Python::check_signals` and calls the progress callback. A
//! `KeyboardInterrupt` (or any exception from the callback) raises the
//! render's cancel flag; the worker stops after the tiles in flight, and
//! the exception is raised once it has stopped, so no render thread
//! outlives the call.

use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::mpsc::{self, RecvTimeoutError};
use std::sync::Arc;
use std::time::{Duration, Instant};

use niebla::film::{Image, SampleSums};
use niebla::integrator::IntegratorSettings;
use niebla::progressive::{resume_progressive_sums, Accumulator, Budget, PassInfo, ProgressiveOptions};
use niebla::scene::BuiltScene;
use pyo3::prelude::*;

use crate::RenderError;

/// How often the waiting thread checks for signals and reports progress.
const POLL_INTERVAL: Duration = Duration::from_millis(50);

/// What to render.
#[derive(Clone, Copy, Debug)]
pub(crate) struct RenderRequest {
    /// Integrator and its parameters.
    pub settings: IntegratorSettings,
    /// Sampler seed.
    pub seed: u64,
    /// When to stop.
    pub budget: Budget,
    /// Worker threads; `None` uses all cores.
    pub threads: Option<usize>,
    /// Index of the first sample (samples `first_sample ..` are rendered).
    pub first_sample: u64,
    /// The numbers of the camera samples (the scene's `render.sampler`).
    pub sampler: niebla::sampling::SamplerKind,
    /// Layers rendered beside the beauty (`niebla::aov`).
    pub aovs: niebla::aov::AovSet,
}

/// A finished render.
pub(crate) struct RenderDone {
    /// The mean image.
    pub image: Image,
    /// The exact per-pixel sums of the samples rendered.
    pub sums: SampleSums,
    /// Samples per pixel rendered.
    pub spp: u64,
    /// Wall-clock seconds.
    pub seconds: f64,
    /// The layer images (`None` when no layers were asked for).
    pub layers: Option<niebla::aov::AovImage>,
}

/// Render `request` on a worker thread; see the module documentation.
pub(crate) fn render_blocking(
    py: Python<'_>,
    built: Arc<BuiltScene>,
    request: RenderRequest,
    progress: Option<&Bound<'_, PyAny>>,
) -> PyResult<RenderDone> {
    let scene = &built.scene;
    let pixels = scene.camera.width as u64 * scene.camera.height as u64;
    let total = match request.budget {
        Budget::Samples(spp) => pixels * spp as u64,
        Budget::Time(limit) => limit.as_millis().max(1) as u64,
    };
    let cancel = AtomicBool::new(false);
    let samples_before_pass = AtomicU64::new(0);
    let samples_in_pass = AtomicU64::new(0);
    let start = Instant::now();
    let done_so_far = || match request.budget {
        Budget::Samples(_) => {
            (samples_before_pass.load(Ordering::Relaxed) + samples_in_pass.load(Ordering::Relaxed)).min(total)
        }
        Budget::Time(_) => (start.elapsed().as_millis() as u64).min(total),
    };

    std::thread::scope(|s| {
        let (sender, receiver) = mpsc::channel();
        let (cancel, samples_before_pass, samples_in_pass) = (&cancel, &samples_before_pass, &samples_in_pass);
        s.spawn(move || {
            let on_progress = |done: u64, _total: u64| samples_in_pass.store(done, Ordering::Relaxed);
            let on_pass = |_: &Accumulator, info: PassInfo| {
                samples_before_pass.store(info.spp * pixels, Ordering::Relaxed);
                samples_in_pass.store(0, Ordering::Relaxed);
                true
            };
            let options = ProgressiveOptions {
                settings: &request.settings,
                seed: request.seed,
                threads: request.threads,
                sampler: request.sampler,
                budget: request.budget,
                progress: &on_progress,
                cancel: Some(cancel),
                aovs: request.aovs,
            };
            let start = Accumulator::starting_at(scene.camera.width, scene.camera.height, request.first_sample);
            let result = resume_progressive_sums(scene, &options, start, on_pass);
            // The receiver only goes away if the caller panicked.
            let _ = sender.send(result.map_err(|e| e.to_string()));
        });

        let mut receiver = receiver;
        let mut raised: Option<PyErr> = None;
        let mut reported = None;
        let result = loop {
            // Wait with the GIL released; the receiver travels into the
            // closure and back (it is Send but not Sync).
            let (received, back) = py.allow_threads(move || (receiver.recv_timeout(POLL_INTERVAL), receiver));
            receiver = back;
            match received {
                Ok(result) => break result,
                Err(RecvTimeoutError::Disconnected) => break Err("the render thread stopped without a result".into()),
                Err(RecvTimeoutError::Timeout) => {}
            }
            if raised.is_some() {
                continue;
            }
            // Ctrl-C, then progress; either may raise, which cancels the render.
            let step = py.check_signals().and_then(|()| match progress {
                Some(callback) => {
                    let done = done_so_far();
                    if reported == Some(done) {
                        return Ok(());
                    }
                    reported = Some(done);
                    callback.call1((done, total)).map(drop)
                }
                None => Ok(()),
            });
            if let Err(e) = step {
                cancel.store(true, Ordering::Relaxed);
                raised = Some(e);
            }
        };
        if let Some(e) = raised {
            return Err(e);
        }
        let acc = result.map_err(RenderError::new_err)?;
        if let Some(callback) = progress {
            if reported != Some(total) {
                callback.call1((total, total))?;
            }
        }
        Ok(RenderDone {
            image: acc.image(),
            spp: acc.spp,
            sums: acc.sums().clone(),
            seconds: start.elapsed().as_secs_f64(),
            layers: acc.aov_image(),
        })
    })
}
