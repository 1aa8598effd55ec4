//! [`CliError`], the one error type of the `niebla` command. Every command
//! returns it; `main` prints it as `error: MESSAGE` on stderr and exits with
//! [`CliError::exit_code`]. Each message names what is wrong first: the
//! option (`--spp: ...`), the file (`fog.json: media.fog.sigma_s[2]: ...`)
//! or the checkpoint (`--resume: ...`).

use std::path::PathBuf;

use niebla::film::{CheckpointError, OutputError};
use niebla::limits::format_bytes;
use niebla::render::RenderError;
use niebla::scene::SceneError;

/// Why a `niebla` command failed.
#[derive(Debug, thiserror::Error)]
pub enum CliError {
    /// A command-line option has a value the command cannot use.
    #[error("{option}: {problem}")]
    InvalidOption {
        /// The option as typed, e.g. `--spp`.
        option: &'static str,
        /// What is wrong with its value, e.g. `must be at least 1`.
        problem: String,
    },
    /// The integrator options (`--integrator`, `--sampling`, `--max-depth`,
    /// `--integrators`) do not fit the integrator; the message comes from
    /// the settings parser and names the option.
    #[error("{0}")]
    Integrator(String),
    /// A voxel file given on the command line (e.g. `niebla info FILE.vdb`)
    /// could not be read; the message names the file and what is wrong.
    #[error("{0}")]
    Volume(#[from] niebla_volume::VolumeError),
    /// `niebla view` could not start (the scene's or the socket's message).
    #[error("{0}")]
    View(String),
    /// The scene file named on the command line does not exist.
    #[error("{}: scene file not found", .0.display())]
    SceneNotFound(PathBuf),
    /// The scene is invalid, or building it went over the memory limit
    /// (then the message says how to raise the limit).
    #[error("{error}{}", if *.over_memory_limit { " (raise it with --max-memory)" } else { "" })]
    Scene {
        /// Where in the scene file and what.
        error: SceneError,
        /// Whether the error is the memory limit refusing a grid or file.
        over_memory_limit: bool,
    },
    /// The scene suits no measurement of this command.
    #[error("{}: {problem}", scene.display())]
    SceneUnsuitable {
        /// The scene file.
        scene: PathBuf,
        /// What the scene lacks.
        problem: &'static str,
    },
    /// The image and its buffers alone would exceed the memory limit.
    #[error(
        "{scene}: camera.width, camera.height: rendering {width} x {height} pixels would need about {} for the \
         image and its output buffers, over the memory limit of {} (lower the resolution or raise --max-memory)",
        format_bytes(*.bytes),
        format_bytes(*.limit)
    )]
    ImageOverMemoryLimit {
        /// The scene, as named in messages.
        scene: String,
        /// Image width in pixels.
        width: u32,
        /// Image height in pixels.
        height: u32,
        /// Estimated bytes of the image and its output buffers.
        bytes: u64,
        /// The memory limit in bytes.
        limit: u64,
    },
    /// An integrator's precomputation (photon maps, lattices) would exceed
    /// what is left of the memory limit.
    #[error(
        "{scene}: render.integrator.{field}: {what} would need about {}, over the {} left of the memory limit \
         (lower render.integrator.{field} or raise --max-memory)",
        format_bytes(*.bytes),
        format_bytes(*.left)
    )]
    PrecomputeOverMemoryLimit {
        /// The scene, as named in messages.
        scene: String,
        /// The field under `render.integrator` that sets the size.
        field: &'static str,
        /// What takes the memory, in words.
        what: String,
        /// Estimated peak bytes.
        bytes: u64,
        /// Bytes left of the memory limit.
        left: u64,
    },
    /// A file of a frame of a sequence does not exist (found before any
    /// frame is rendered).
    #[error(
        "{scene}: frame {frame}: {field}: {} not found (the first missing file of frames {range}; nothing was rendered)",
        file.display()
    )]
    FrameFileMissing {
        /// The scene, as named in messages.
        scene: String,
        /// The frame number.
        frame: u32,
        /// The JSON path of the `file` field.
        field: String,
        /// The file as resolved against the scene's folder.
        file: PathBuf,
        /// The frames asked for, as given to `--frames`.
        range: String,
    },
    /// Rendering frame `frame` of a sequence failed.
    #[error("frame {frame}: {error}")]
    Frame {
        /// The frame number.
        frame: u32,
        /// What failed.
        error: Box<CliError>,
    },
    /// An output file name has an extension other than `.exr` or `.png`.
    #[error("{}: output must end in .exr or .png", .0.display())]
    OutputFormat(PathBuf),
    /// The folder of an output file does not exist.
    #[error("{}: output folder {} does not exist", path.display(), folder.display())]
    OutputFolderMissing {
        /// The output file.
        path: PathBuf,
        /// Its folder.
        folder: PathBuf,
    },
    /// The `--resume` checkpoint could not be read.
    #[error("--resume: {0}")]
    CheckpointUnreadable(CheckpointError),
    /// The `--resume` checkpoint does not continue this render.
    #[error("--resume: {} {problem}", path.display())]
    CheckpointMismatch {
        /// The checkpoint.
        path: PathBuf,
        /// How it differs, e.g. `was rendered with seed 3, not --seed 4`.
        problem: String,
    },
    /// An input of `niebla merge` cannot be merged with the others.
    #[error("merge: {}: {problem}", path.display())]
    Merge {
        /// The input file.
        path: PathBuf,
        /// Why, e.g. `was rendered with seed 3, not seed 4 as a.exr`.
        problem: String,
    },
    /// `niebla compare --reference` names a file that does not exist.
    #[error("{}: reference image not found", .0.display())]
    ReferenceNotFound(PathBuf),
    /// The reference image exists but is not a readable EXR.
    #[error("{}: could not read the reference EXR: {reason}", path.display())]
    ReferenceUnreadable {
        /// The reference image.
        path: PathBuf,
        /// What is wrong, without the file name.
        reason: String,
    },
    /// The reference image is not at the scene's resolution.
    #[error("{}: the reference is {}x{} but the scene renders {}x{}", path.display(), size.0, size.1, scene_size.0, scene_size.1)]
    ReferenceSize {
        /// The reference image.
        path: PathBuf,
        /// Its width and height in pixels.
        size: (u32, u32),
        /// The scene camera's width and height in pixels.
        scene_size: (u32, u32),
    },
    /// Rendering failed.
    #[error(transparent)]
    Render(#[from] RenderError),
    /// An image or report could not be written.
    #[error(transparent)]
    Output(#[from] OutputError),
    /// A file or folder other than the scene could not be read or made.
    #[error("{}: {error}", path.display())]
    Io {
        /// The file or folder.
        path: PathBuf,
        /// Underlying error.
        error: std::io::Error,
    },
    /// An image of the compare report could not be encoded as PNG.
    #[error(transparent)]
    Png(#[from] png::EncodingError),
    /// A plot of the compare report could not be drawn.
    #[error("could not draw the plot: {0}")]
    Plot(String),
}

impl CliError {
    /// `option: problem` for an option value the command cannot use.
    pub fn invalid_option(option: &'static str, problem: impl Into<String>) -> CliError {
        CliError::InvalidOption { option, problem: problem.into() }
    }

    /// The process exit status for this error: 1 for every failure of a
    /// command (clap itself exits with 2 for a command line it cannot parse).
    pub fn exit_code(&self) -> u8 {
        1
    }
}
