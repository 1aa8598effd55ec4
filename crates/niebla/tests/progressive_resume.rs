//! A progressive render continued from any of its checkpoints (the f32
//! mean image and its sample count) ends bit-identical to one that was
//! never stopped, whatever the thread counts, with either sampler.

use std::path::Path;

use niebla::film::Image;
use niebla::progressive::{render_progressive, resume_progressive, Accumulator, Budget, ProgressiveOptions};
use niebla::sampling::SamplerKind;
use niebla::scene::{build_scene, parse_scene_str, DEFAULT_SCENE};

fn bits(image: &Image) -> Vec<[u32; 3]> {
    image.pixels.iter().map(|p| p.0.map(f32::to_bits)).collect()
}

#[test]
fn resumed_progressive_render_is_bit_identical_to_an_uninterrupted_one() {
    for sampler in SamplerKind::ALL {
        resumed_render_is_bit_identical(sampler);
    }
}

fn resumed_render_is_bit_identical(sampler: SamplerKind) {
    let desc = parse_scene_str(DEFAULT_SCENE, "<default>").unwrap();
    let mut built = build_scene(&desc, "<default>", Path::new(".")).unwrap();
    built.scene.camera.width = 29;
    built.scene.camera.height = 19;
    let (scene, settings) = (&built.scene, built.settings.integrator);

    // Uninterrupted, keeping every checkpoint.
    let mut checkpoints = Vec::new();
    let options =
        |threads| ProgressiveOptions { threads, sampler, ..ProgressiveOptions::new(&settings, 5, Budget::Samples(16)) };
    let straight = render_progressive(scene, &options(Some(2)), |im, info| {
        checkpoints.push((im.clone(), info.spp));
        true
    })
    .unwrap();
    assert_eq!(checkpoints.iter().map(|c| c.1).collect::<Vec<_>>(), [1, 2, 4, 8, 16]);
    assert_eq!(bits(&straight), bits(&checkpoints[4].0));

    // Continued from each checkpoint, on another thread count.
    for (image, spp) in &checkpoints[..4] {
        let start = Accumulator::from_mean(image.clone(), *spp);
        let resumed = resume_progressive(scene, &options(Some(1)), start, |_, _| true).unwrap();
        assert!(bits(&resumed) == bits(&straight), "{sampler:?}: resumed from {spp} spp differs");
    }
    // Nothing left to do: the checkpoint itself.
    let start = Accumulator::from_mean(straight.clone(), 16);
    let same_options = ProgressiveOptions { sampler, ..ProgressiveOptions::new(&settings, 5, Budget::Samples(8)) };
    let same = resume_progressive(scene, &same_options, start, |_, _| true).unwrap();
    assert_eq!(bits(&same), bits(&straight));
}
