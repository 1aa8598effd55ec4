//! `niebla render --frames`: a sequence, each frame rendered with the
//! scene's settings. Every frame's scene is read and its files checked
//! before the first frame renders; frames whose output exists are skipped
//! unless `--overwrite`; meshes, textures and environment maps whose names
//! have no frame pattern are read once ([`niebla::scene::SceneCache`]).
//!
//! A frame's outputs are written once, when it is finished (to a temporary
//! file renamed into place, as every output is), so an output that exists
//! is a finished frame: a sequence stopped at any time and started again
//! continues with the first unfinished frame.

use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use indicatif::{MultiProgress, ProgressBar, ProgressDrawTarget, ProgressStyle};
use niebla::scene::frames::{file_fields, has_frame_pattern, substitute_frame, FrameNumber};
use niebla::scene::SceneCache;

use crate::error::CliError;
use crate::render_cmd::{output_paths, render_loaded, RenderArgs};

/// The frames of `--frames`: `N`, `FIRST-LAST` or `FIRST-LAST:STEP`.
///
/// Errors name what is wrong with the text.
pub fn parse_frame_range(text: &str) -> Result<Vec<FrameNumber>, String> {
    let number = |s: &str, what: &str| -> Result<u64, String> {
        let s = s.trim();
        if s.is_empty() || !s.bytes().all(|b| b.is_ascii_digit()) {
            return Err(format!(
                "{text:?}: the {what} must be a whole number >= 0, got {s:?} (expected N, FIRST-LAST or FIRST-LAST:STEP)"
            ));
        }
        s.parse::<u64>().map_err(|_| format!("{text:?}: the {what} {s} is too large"))
    };
    let (range, step) = match text.split_once(':') {
        Some((r, s)) => (r, number(s, "step")?),
        None => (text, 1),
    };
    if step == 0 {
        return Err(format!("{text:?}: the step must be at least 1"));
    }
    let (first, last) = match range.split_once('-') {
        Some((a, b)) => (number(a, "first frame")?, number(b, "last frame")?),
        None => {
            if text.contains(':') {
                return Err(format!("{text:?}: a step needs a range, FIRST-LAST:STEP"));
            }
            let n = number(range, "frame")?;
            (n, n)
        }
    };
    if first > last {
        return Err(format!("{text:?}: the first frame ({first}) is after the last ({last})"));
    }
    if last > u64::from(u32::MAX) {
        return Err(format!("{text:?}: frame numbers must be at most {}", u32::MAX));
    }
    if (last - first) / step >= 1_000_000 {
        return Err(format!("{text:?}: more than a million frames"));
    }
    Ok((first..=last).step_by(step as usize).map(|f| f as FrameNumber).collect())
}

/// The output file of `frame` from the `-o` pattern.
fn frame_output(pattern: &Path, frame: FrameNumber) -> Result<PathBuf, CliError> {
    let text = pattern.to_string_lossy();
    substitute_frame(&text, frame).map(PathBuf::from).map_err(|problem| CliError::invalid_option("-o", problem))
}

/// The files that must exist for a frame to be finished: its outputs and,
/// with --denoise, their denoised images.
fn finished_files(outputs: &[PathBuf], denoise: bool) -> Vec<PathBuf> {
    let mut files = outputs.to_vec();
    if denoise {
        files.extend(outputs.iter().map(|o| niebla::denoise::denoised_path(o)));
    }
    files
}

/// `niebla render --frames RANGE`.
pub fn run(args: &RenderArgs, range: &str) -> Result<(), CliError> {
    let frames = parse_frame_range(range).map_err(|p| CliError::invalid_option("--frames", p))?;
    let Some(scene) = args.scene.as_deref() else {
        return Err(CliError::invalid_option("--frames", "needs a scene file (the built-in scene is not animated)"));
    };
    let Some(pattern) = args.output.as_deref() else {
        return Err(CliError::invalid_option(
            "--frames",
            "needs -o with a frame pattern naming each frame's output, e.g. -o out.####.exr",
        ));
    };
    let pattern_text = pattern.to_string_lossy();
    if !has_frame_pattern(&pattern_text) {
        return Err(CliError::invalid_option(
            "-o",
            format!(
                "{pattern_text}: with --frames the output needs a frame pattern (#### for the zero-padded frame \
                 number, {{frame}} or {{frame:04}}), e.g. out.####.exr"
            ),
        ));
    }
    let max_memory = args.max_memory.limit();
    let defines = &args.define.define;

    // Every frame's scene is read and its files checked before anything renders.
    let mut plan = Vec::with_capacity(frames.len());
    for &frame in &frames {
        let read = crate::load::read_frame(scene, defines, frame).map_err(|e| in_frame(frame, e))?;
        for (field, name) in file_fields(&read.value) {
            let file = read.base.join(&name);
            if !file.exists() {
                return Err(CliError::FrameFileMissing {
                    scene: read.source.clone(),
                    frame,
                    field,
                    file,
                    range: range.to_string(),
                });
            }
        }
        let outputs = output_paths(Some(&frame_output(pattern, frame)?), &read.stem)?;
        plan.push((frame, outputs));
    }

    let multi = if args.quiet.quiet {
        MultiProgress::with_draw_target(ProgressDrawTarget::hidden())
    } else {
        MultiProgress::new()
    };
    let print = |line: String| multi.suspend(|| println!("{line}"));
    let todo: Vec<_> = plan
        .into_iter()
        .filter(|(frame, outputs)| {
            let done = finished_files(outputs, args.denoise).iter().all(|f| f.exists());
            if done && !args.overwrite {
                let names: Vec<String> = outputs.iter().map(|p| p.display().to_string()).collect();
                print(format!("frame {frame}: skipped, {} exists (--overwrite renders it again)", names.join(", ")));
            }
            args.overwrite || !done
        })
        .collect();
    let skipped = frames.len() - todo.len();

    let overall = multi.add(ProgressBar::new(todo.len() as u64));
    overall.set_style(
        ProgressStyle::with_template("frames {pos}/{len} [{elapsed_precise}] {msg}")
            .expect("the progress bar template is valid"),
    );
    overall.set_message(format!("{skipped} of {} already done", frames.len()));
    let cache = SceneCache::default();
    let start = Instant::now();
    let mut rendering = Duration::ZERO;
    for (done, (frame, outputs)) in todo.iter().enumerate() {
        let frame_start = Instant::now();
        let render_frame = || -> Result<Option<String>, CliError> {
            let read = crate::load::read_frame(scene, defines, *frame)?;
            for note in &read.notes {
                multi.suspend(|| eprintln!("note: {note}"));
            }
            let loaded = crate::load::build_read(read, max_memory, &cache)?;
            let bar = multi.insert_before(&overall, ProgressBar::new(1));
            render_loaded(args, loaded, outputs, bar, false)
        };
        let line = render_frame().map_err(|e| in_frame(*frame, e))?;
        let seconds = frame_start.elapsed();
        rendering += seconds;
        if let Some(line) = line {
            print(format!("frame {frame}: {line}"));
        }
        let left = todo.len() - done - 1;
        let mean = rendering / (done as u32 + 1);
        overall.inc(1);
        overall.set_message(format!(
            "last frame {:.2} s, mean {:.2} s per frame, ETA {}",
            seconds.as_secs_f64(),
            mean.as_secs_f64(),
            indicatif::HumanDuration(mean * left as u32)
        ));
    }
    overall.finish_and_clear();
    print(format!(
        "rendered {} of {} frames in {:.2} s ({skipped} skipped: their outputs existed)",
        todo.len(),
        frames.len(),
        start.elapsed().as_secs_f64()
    ));
    Ok(())
}

/// `error` as an error of frame `frame` (scene errors name the frame).
fn in_frame(frame: FrameNumber, error: CliError) -> CliError {
    CliError::Frame { frame, error: Box::new(error) }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ranges_steps_and_single_frames() {
        assert_eq!(parse_frame_range("1-5").unwrap(), vec![1, 2, 3, 4, 5]);
        assert_eq!(parse_frame_range("1-10:4").unwrap(), vec![1, 5, 9]);
        assert_eq!(parse_frame_range("7").unwrap(), vec![7]);
        assert_eq!(parse_frame_range("0-0").unwrap(), vec![0]);
        for (bad, says) in [
            ("5-1", "is after the last"),
            ("1-5:0", "step must be at least 1"),
            ("a-5", "first frame must be a whole number"),
            ("1-", "last frame must be a whole number"),
            ("-3", "first frame must be a whole number"),
            ("7:2", "a step needs a range"),
            ("1-99999999999", "at most"),
            ("", "frame must be a whole number"),
        ] {
            let e = parse_frame_range(bad).unwrap_err();
            assert!(e.contains(says), "{bad}: {e}");
        }
    }
}
