//! The state a viewer shares between its page requests and its render
//! threads: the scene as the page last edited it (JSON, validated by the
//! scene parser), the comparison integrator, and the latest frame or error
//! of each of the two render slots (slot 0: the scene's integrator; slot 1:
//! the comparison integrator of the split view).

use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Condvar, Mutex, MutexGuard};
use std::time::{Duration, Instant};

use serde_json::Value;

use crate::frame::Frame;

/// What the render slots are asked to render.
#[derive(Clone, Debug)]
pub struct Job {
    /// Edit count; a slot restarts when it changes.
    pub version: u64,
    /// The scene, as JSON that parsed and validated.
    pub scene: Arc<Value>,
    /// The comparison integrator's `render.integrator` object (split view), if any.
    pub compare: Option<Arc<Value>>,
    /// Render one pass at reduced resolution (the page is dragging a control).
    pub interactive: bool,
    /// Divisor of width and height during interactive frames (1 to 16).
    pub preview_scale: u32,
    /// Stop refining after this many samples per pixel.
    pub max_spp: u32,
    /// When the edit that made this job arrived at the server (`None`: the
    /// initial scene or a reload from disk): where a frame's latency starts.
    pub edited_at: Option<Instant>,
    /// Seconds the server spent validating that edit.
    pub validate_seconds: f64,
}

/// Everything that decides what one slot renders (two jobs with equal
/// inputs for a slot give the same frames there).
#[derive(Clone, Debug, PartialEq)]
pub struct SlotInput {
    /// The scene the slot renders (`None`: the slot is idle).
    pub scene: Option<Value>,
    /// Reduced resolution, one pass.
    pub interactive: bool,
    /// Divisor of the resolution while interactive.
    pub preview_scale: u32,
    /// Samples per pixel to stop at.
    pub max_spp: u32,
}

impl Job {
    /// What slot `index` renders for this job.
    pub fn slot_input(&self, index: usize) -> SlotInput {
        SlotInput {
            scene: crate::render_loop::slot_scene(self, index),
            interactive: self.interactive,
            preview_scale: self.preview_scale,
            max_spp: self.max_spp,
        }
    }
}

/// What a render slot last produced.
#[derive(Clone, Debug)]
pub enum Event {
    /// Nothing yet.
    None,
    /// A frame.
    Frame(Arc<Frame>),
    /// The scene of version `.0` could not be built or rendered: the message.
    Error(u64, u64, String),
}

impl Event {
    /// The event's sequence number within its slot (0 for `None`).
    pub fn id(&self) -> u64 {
        match self {
            Event::None => 0,
            Event::Frame(f) => f.id,
            Event::Error(_, id, _) => *id,
        }
    }
}

/// One render slot's latest event and a condition variable that wakes the
/// page's long-polling requests.
#[derive(Default)]
pub struct Slot {
    event: Mutex<Option<Event>>,
    changed: Condvar,
    /// Raised to cancel the slot's render (an edit arrived).
    pub cancel: AtomicBool,
    /// Set while the slot renders an interactive (drag) frame.
    pub rendering_interactive: AtomicBool,
}

impl Slot {
    /// Publish a frame (its `id` is replaced by the next sequence number).
    pub fn publish_frame(&self, mut frame: Frame) {
        let mut event = lock(&self.event);
        frame.id = event.as_ref().map_or(0, Event::id) + 1;
        *event = Some(Event::Frame(Arc::new(frame)));
        self.changed.notify_all();
    }

    /// Publish an error of scene version `version`.
    pub fn publish_error(&self, version: u64, message: String) {
        let mut event = lock(&self.event);
        let id = event.as_ref().map_or(0, Event::id) + 1;
        *event = Some(Event::Error(version, id, message));
        self.changed.notify_all();
    }

    /// The latest event.
    pub fn latest(&self) -> Event {
        lock(&self.event).clone().unwrap_or(Event::None)
    }

    /// The first event newer than `after`, waiting at most `timeout` or
    /// until `stop` is raised (`Event::None` when none came).
    pub fn wait_after(&self, after: u64, timeout: Duration, stop: &AtomicBool) -> Event {
        let guard = lock(&self.event);
        let (guard, _) = self
            .changed
            .wait_timeout_while(guard, timeout, |e| {
                e.as_ref().map_or(0, Event::id) <= after && !stop.load(Ordering::SeqCst)
            })
            .unwrap_or_else(|p| p.into_inner());
        match guard.as_ref() {
            Some(e) if e.id() > after => e.clone(),
            _ => Event::None,
        }
    }

    /// Wake the waiters (at shutdown).
    fn wake(&self) {
        self.changed.notify_all();
    }
}

/// Lock a mutex, going on with the data if a thread panicked while holding it.
pub fn lock<T>(m: &Mutex<T>) -> MutexGuard<'_, T> {
    m.lock().unwrap_or_else(|p| p.into_inner())
}

/// The shared state of one viewer.
pub struct Session {
    /// The scene file viewed (`None`: the built-in default scene).
    pub scene_path: Option<PathBuf>,
    /// The folder relative paths resolve against and saved files go to.
    pub base: PathBuf,
    /// The name errors show for the scene (the file as given, or `<default>`).
    pub label: String,
    /// The `file` values the original scene names (allowed even outside the folder).
    pub original_files: Vec<String>,
    /// Worker threads of the renders (`None`: all cores).
    pub threads: Option<usize>,
    job: Mutex<Job>,
    job_changed: Condvar,
    /// Incremented when the scene file changed on disk and was reloaded.
    reloads: Mutex<u64>,
    /// The two render slots.
    pub slots: [Slot; 2],
    /// Raised at shutdown.
    pub stop: AtomicBool,
}

impl Session {
    /// A session showing `scene` (already validated).
    pub fn new(
        scene_path: Option<PathBuf>,
        base: PathBuf,
        label: String,
        scene: Value,
        threads: Option<usize>,
    ) -> Session {
        let original_files = crate::paths::file_fields(&scene).into_iter().map(|(_, f)| f).collect();
        let job = Job {
            version: 1,
            scene: Arc::new(scene),
            compare: None,
            interactive: false,
            preview_scale: 2,
            max_spp: 1 << 16,
            edited_at: None,
            validate_seconds: 0.0,
        };
        Session {
            scene_path,
            base,
            label,
            original_files,
            threads,
            job: Mutex::new(job),
            job_changed: Condvar::new(),
            reloads: Mutex::new(0),
            slots: [Slot::default(), Slot::default()],
            stop: AtomicBool::new(false),
        }
    }

    /// The current job.
    pub fn job(&self) -> Job {
        lock(&self.job).clone()
    }

    /// Replace the job through `edit` (which sees the current one), give it
    /// the next version, cancel the renders of the slots whose input
    /// changed (the split view's switch leaves slot 0 refining) and wake
    /// the slots.
    pub fn update_job(&self, edit: impl FnOnce(&mut Job)) -> u64 {
        let mut job = lock(&self.job);
        let before = [job.slot_input(0), job.slot_input(1)];
        edit(&mut job);
        job.version += 1;
        for (index, slot) in self.slots.iter().enumerate() {
            // A drag frame in progress is finished, not cancelled, by the next
            // drag edit (the slot then renders the latest one), so the image
            // follows the mouse at the rate frames can be rendered.
            let keep = job.interactive && slot.rendering_interactive.load(Ordering::SeqCst);
            if job.slot_input(index) != before[index] && !keep {
                slot.cancel.store(true, Ordering::SeqCst);
            }
        }
        self.job_changed.notify_all();
        job.version
    }

    /// The scene was reloaded from disk.
    pub fn note_reload(&self) {
        *lock(&self.reloads) += 1;
    }

    /// How many times the scene file was reloaded.
    pub fn reloads(&self) -> u64 {
        *lock(&self.reloads)
    }

    /// Wait until the job's version differs from `seen` (or shutdown);
    /// `None` at shutdown.
    pub fn wait_job(&self, seen: u64) -> Option<Job> {
        let mut job = lock(&self.job);
        loop {
            if self.stop.load(Ordering::SeqCst) {
                return None;
            }
            if job.version != seen {
                return Some(job.clone());
            }
            job = self.job_changed.wait_timeout(job, Duration::from_millis(500)).unwrap_or_else(|p| p.into_inner()).0;
        }
    }

    /// Stop the render slots and wake every waiter.
    pub fn shut_down(&self) {
        self.stop.store(true, Ordering::SeqCst);
        for slot in &self.slots {
            slot.cancel.store(true, Ordering::SeqCst);
            slot.wake();
        }
        let _guard = lock(&self.job);
        self.job_changed.notify_all();
    }
}
