//! `niebla merge`: adds up the exact sums of EXR renders of disjoint
//! sample ranges of one scene (same scene hash, seed, integrator and size)
//! into one EXR, whose image is bit-identical to one render of all those
//! samples (the sums are exact fixed-point integers, `niebla::film::SampleSums`).

use std::path::{Path, PathBuf};

use clap::Args;
use niebla::film::{read_checkpoint_full, write_checkpoint, CheckpointInfo, SampleSums};

use crate::error::CliError;
use crate::flags::check_output_folder;

/// Options of `niebla merge`.
#[derive(Args, Debug)]
pub struct MergeArgs {
    /// EXR outputs of `niebla render` (e.g. with --first-sample/--spp, one
    /// per machine) of the same scene file, seed and integrator, over
    /// disjoint sample ranges.
    #[arg(required = true, value_name = "INPUT.exr")]
    pub inputs: Vec<PathBuf>,
    /// The merged EXR: the mean over all the inputs' samples (weighted by
    /// their sample counts), with the sums and sample ranges in its header,
    /// so it can be merged again or continued with `niebla render --resume`
    /// when its ranges are contiguous.
    #[arg(short, long, value_name = "OUTPUT.exr")]
    pub output: PathBuf,
}

/// One input: its file, header and sums.
struct Input {
    path: PathBuf,
    info: CheckpointInfo,
    sums: SampleSums,
}

/// `niebla merge`.
pub fn run(args: &MergeArgs) -> Result<(), CliError> {
    if !args.output.extension().is_some_and(|e| e.eq_ignore_ascii_case("exr")) {
        return Err(CliError::invalid_option("--output", format!("{}: must end in .exr", args.output.display())));
    }
    check_output_folder(&args.output)?;
    let inputs = args.inputs.iter().map(|p| read_input(p)).collect::<Result<Vec<_>, _>>()?;
    let first = &inputs[0];
    for input in &inputs[1..] {
        check_compatible(first, input)?;
    }
    let ranges = merged_ranges(&inputs)?;
    let mut sums = SampleSums::new(first.sums.width, first.sums.height);
    for input in &inputs {
        sums.add(&input.sums);
    }
    let spp = inputs.iter().map(|i| i.info.spp).sum();
    let info = CheckpointInfo { spp, ranges, ..first.info.clone() };
    write_checkpoint(&sums, &info, &args.output)?;
    println!(
        "merged {} renders: {spp} spp (samples {}) -> {}",
        inputs.len(),
        CheckpointInfo::ranges_text(&info.ranges),
        args.output.display()
    );
    Ok(())
}

/// Reads one input, which must carry exact sums.
fn read_input(path: &Path) -> Result<Input, CliError> {
    let problem = |problem: String| CliError::Merge { path: path.to_path_buf(), problem };
    let checkpoint = read_checkpoint_full(path).map_err(|e| {
        let text = e.to_string();
        let prefix = format!("{}: ", path.display());
        problem(text.strip_prefix(&prefix).map(str::to_string).unwrap_or(text))
    })?;
    let Some(sums) = checkpoint.sums else {
        return Err(problem(
            "was written by an older niebla (checkpoint format 1, the mean alone) and carries no exact sums; \
             render it again"
                .to_string(),
        ));
    };
    Ok(Input { path: path.to_path_buf(), info: checkpoint.info, sums })
}

/// Refuses `input` unless it renders the same scene, seed, integrator and
/// image size as `first`.
fn check_compatible(first: &Input, input: &Input) -> Result<(), CliError> {
    let (a, b) = (&first.info, &input.info);
    let name = first.path.display();
    let problem = if b.scene_hash != a.scene_hash {
        format!("was rendered from another scene (scene hash {}, {name}: {})", b.scene_hash, a.scene_hash)
    } else if b.seed != a.seed {
        format!("was rendered with seed {}, {name} with seed {}", b.seed, a.seed)
    } else if b.integrator != a.integrator {
        format!("was rendered with integrator {}, {name} with {}", b.integrator, a.integrator)
    } else if (input.sums.width, input.sums.height) != (first.sums.width, first.sums.height) {
        format!(
            "is {} x {} pixels, {name} {} x {}",
            input.sums.width, input.sums.height, first.sums.width, first.sums.height
        )
    } else {
        return Ok(());
    };
    Err(CliError::Merge { path: input.path.clone(), problem })
}

/// The sample ranges of all inputs, sorted, with touching ranges joined;
/// refuses inputs whose ranges overlap (their samples would count twice).
fn merged_ranges(inputs: &[Input]) -> Result<Vec<(u64, u64)>, CliError> {
    let mut all: Vec<((u64, u64), &Path)> =
        inputs.iter().flat_map(|i| i.info.ranges.iter().map(move |&r| (r, i.path.as_path()))).collect();
    all.sort_by_key(|&(r, _)| r);
    let mut merged: Vec<(u64, u64)> = Vec::new();
    for pair in all.windows(2) {
        let ((a, path_a), (b, path_b)) = (pair[0], pair[1]);
        if b.0 < a.1 {
            return Err(CliError::Merge {
                path: path_b.to_path_buf(),
                problem: format!(
                    "its samples {}..{} overlap samples {}..{} of {} (each sample may be counted once)",
                    b.0,
                    b.1,
                    a.0,
                    a.1,
                    path_a.display()
                ),
            });
        }
    }
    for ((start, end), _) in all {
        match merged.last_mut() {
            Some(last) if last.1 == start => last.1 = end,
            _ => merged.push((start, end)),
        }
    }
    Ok(merged)
}
