//! A progressive render continued from any of its checkpoints (the exact
//! per-pixel sums and their sample range) ends bit-identical to one that
//! was never stopped, whatever the thread counts, and to one render of all
//! the samples; sample ranges rendered apart add up to it too; with either
//! sampler.

use std::path::Path;

use niebla::film::Image;
use niebla::progressive::{
    render_progressive, resume_progressive, resume_progressive_sums, Accumulator, Budget, ProgressiveOptions,
};
use niebla::render::{render, render_sums, RenderOptions};
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
    let start = Accumulator::new(scene.camera.width, scene.camera.height);
    let straight = resume_progressive_sums(scene, &options(Some(2)), start, |acc, _| {
        checkpoints.push(acc.clone());
        true
    })
    .unwrap()
    .image();
    assert_eq!(checkpoints.iter().map(|c| c.spp).collect::<Vec<_>>(), [1, 2, 4, 8, 16]);
    assert_eq!(bits(&straight), bits(&checkpoints[4].image()));
    let means = render_progressive(scene, &options(Some(3)), |_, _| true).unwrap();
    assert_eq!(bits(&means), bits(&straight));

    // One render of the 16 samples, and two ranges rendered apart and added.
    let whole = RenderOptions { spp: 16, seed: 5, first_sample: 0, threads: Some(1), sampler };
    assert_eq!(bits(&render(scene, &settings, &whole, &|_, _| {}, None).unwrap()), bits(&straight));
    let part = |first_sample, spp| {
        let options = RenderOptions { spp, seed: 5, first_sample, threads: Some(2), sampler };
        render_sums(scene, &settings, &options, &|_, _| {}, None).unwrap()
    };
    let mut sums = part(7, 9);
    sums.add(&part(0, 7));
    assert_eq!(bits(&sums.mean(16)), bits(&straight));

    // Continued from each checkpoint, on another thread count.
    for acc in &checkpoints[..4] {
        let start = Accumulator::from_sums(acc.sums().clone(), 0, acc.spp);
        let resumed = resume_progressive(scene, &options(Some(1)), start, |_, _| true).unwrap();
        assert!(bits(&resumed) == bits(&straight), "{sampler:?}: resumed from {} spp differs", acc.spp);
    }
    // Nothing left to do: the checkpoint itself.
    let start = checkpoints[4].clone();
    let same_options = ProgressiveOptions { sampler, ..ProgressiveOptions::new(&settings, 5, Budget::Samples(8)) };
    let same = resume_progressive(scene, &same_options, start, |_, _| true).unwrap();
    assert_eq!(bits(&same), bits(&straight));
}
