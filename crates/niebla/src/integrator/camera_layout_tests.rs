//! Tests of the camera-ray dimension layout: slots, stratification of the
//! decisions whatever the tracking draws before them, independence and
//! uniformity of the numbers past the slots.

use super::*;
use crate::sampling::{hash_u64, SamplerKind};
use glam::Vec2;

/// Every slot lies inside its block, and no two slots share a dimension.
#[test]
fn slots_are_disjoint_and_inside_the_block() {
    let block = [
        DISTANCE,
        EQUIANGULAR,
        LIGHT_POINT,
        EQUIANGULAR_LIGHT_POINT,
        EMISSION_JITTER,
        SCATTER_JITTER,
        SURFACE_LIGHT_POINT,
        SPECULAR_DIRECTION,
        LOBE,
        VOLUME_LIGHT,
        SURFACE_VOLUME_LIGHT,
        TRANSMITTANCE,
    ];
    let step = [STEP_LIGHT_POINT, STEP_VOLUME_LIGHT, STEP_TRANSMITTANCE];
    for (slots, size) in [(&block[..], BLOCK), (&step[..], MARCH_BLOCK)] {
        let mut owner = vec![usize::MAX; size as usize];
        for (i, s) in slots.iter().enumerate() {
            for d in s.offset..s.offset + s.len {
                assert!(d < size, "slot {i} leaves the block");
                assert_eq!(owner[d as usize], usize::MAX, "dimension {d} of slots {} and {i}", owner[d as usize]);
                owner[d as usize] = i;
            }
        }
    }
    // 2D decisions take whole pairs; the volume-light points (choice, pair,
    // third) have their pair on an even dimension.
    for s in [LIGHT_POINT, EQUIANGULAR_LIGHT_POINT, SURFACE_LIGHT_POINT, SPECULAR_DIRECTION] {
        assert_eq!(start(1, s) % 2, 0);
    }
    for s in [VOLUME_LIGHT, SURFACE_VOLUME_LIGHT] {
        assert_eq!((start(1, s) + 1) % 2, 0);
    }
    assert_eq!(march_start(1, 3, STEP_LIGHT_POINT) % 2, 0);
    assert_eq!((march_start(1, 3, STEP_VOLUME_LIGHT) + 1) % 2, 0);
    // The march region starts after the last laid-out block.
    assert!(march_start(0, 0, STEP_LIGHT_POINT) >= start(LAID_OUT_STEPS, DISTANCE));
    assert_eq!(BLOCK % 2, 0);
    assert_eq!(MARCH_BLOCK % 2, 0);
}

/// How many elementary intervals `2^-a x 2^-(k-a)` of `points` (`2^k`
/// of them) hold other than exactly one point.
fn bad_intervals(points: &[Vec2], k: u32) -> usize {
    let mut bad = 0;
    for a in 0..=k {
        let (nx, ny) = (1usize << a, 1usize << (k - a));
        let mut count = vec![0u32; nx * ny];
        for p in points {
            let (i, j) = ((p.x * nx as f32) as usize, (p.y * ny as f32) as usize);
            count[j.min(ny - 1) * nx + i.min(nx - 1)] += 1;
        }
        bad += count.iter().filter(|&&c| c != 1).count();
    }
    bad
}

/// Tracking draws of a sample, varying between samples as those of ratio
/// tracking do: up to `n - 1` numbers.
fn tracking(sampler: &mut PixelSampler, s: u64, salt: u64, n: u64) {
    for _ in 0..hash_u64(s ^ salt) % n {
        sampler.next_1d();
    }
}

/// The decisions of camera sample `s` of one pixel as `single` (`mis`)
/// draws them in its first walk step, with a varying number of tracking
/// draws before each (camera transmittance, transmittance to the sampled
/// point, shadow rays): (distance, equiangular distance), and the light
/// point at the distance-sampled point.
fn single_decisions(kind: SamplerKind, s: u64) -> (Vec2, Vec2) {
    let mut sampler = PixelSampler::for_pixel(kind, 9, 5, 3, s);
    let _pixel = sampler.next_2d();
    sampler.set_layout_block(Some(0));
    enter(&mut sampler, TRANSMITTANCE);
    tracking(&mut sampler, s, 1, 9);
    enter(&mut sampler, DISTANCE);
    let distance = sampler.next_1d();
    tracking(&mut sampler, s, 2, 7);
    let mut light_point = Vec2::ZERO;
    for light in 0..2 {
        enter(&mut sampler, LIGHT_POINT);
        let u = sampler.next_2d();
        if light == 0 {
            light_point = u;
        }
        tracking(&mut sampler, s, 3 + light, 5);
    }
    enter(&mut sampler, EQUIANGULAR);
    let equiangular = sampler.next_1d();
    (Vec2::new(distance, equiangular), light_point)
}

/// `single`'s main decisions over the first `2^k` samples of a pixel are
/// (0, k, 2)-nets (one point in every elementary interval) whatever the
/// tracking draws before them: the distance pair and the light point. In
/// draw order (`sobol_sequential`) they are not: an independent set of 256
/// points leaves about 1/e of the 9 x 256 intervals empty.
#[test]
fn single_decisions_are_stratified_whatever_came_before() {
    let k = 8;
    let points = |kind| -> (Vec<Vec2>, Vec<Vec2>) { (0..1u64 << k).map(|s| single_decisions(kind, s)).unzip() };
    let (distance, light) = points(SamplerKind::Sobol);
    assert_eq!(bad_intervals(&distance, k), 0);
    assert_eq!(bad_intervals(&light, k), 0);
    let (distance, light) = points(SamplerKind::SobolSequential);
    let (bad_distance, bad_light) = (bad_intervals(&distance, k), bad_intervals(&light, k));
    assert!(bad_distance > 500 && bad_light > 500, "{bad_distance} {bad_light}");
}

/// The second walk step's decisions (an emission march's jitter and the
/// point on the light seen from the surface behind the medium) do not
/// depend on how many numbers the first step drew: over `2^k` samples the
/// jitter has one value in each of the `2^k` intervals of [0, 1), and the
/// light point is a (0, k, 2)-net.
#[test]
fn later_walk_steps_are_stratified_whatever_came_before() {
    let k = 8;
    let mut jitters = vec![0u32; 1 << k];
    let mut light = Vec::new();
    for s in 0..1u64 << k {
        let mut sampler = PixelSampler::for_pixel(SamplerKind::Sobol, 2, 7, 1, s);
        let _pixel = sampler.next_2d();
        sampler.set_layout_block(Some(0));
        enter(&mut sampler, EMISSION_JITTER);
        tracking(&mut sampler, s, 5, 40);
        sampler.set_layout_block(Some(1));
        enter(&mut sampler, EMISSION_JITTER);
        jitters[(sampler.next_1d() * (1 << k) as f32) as usize] += 1;
        tracking(&mut sampler, s, 6, 40);
        enter(&mut sampler, SURFACE_LIGHT_POINT);
        light.push(sampler.next_2d());
    }
    assert!(jitters.iter().all(|&c| c == 1), "{jitters:?}");
    assert_eq!(bad_intervals(&light, k), 0);
}

/// Ray-march steps: the light point of step 5 is a (0, k, 2)-net over the
/// pixel's samples, and the first tracking number of step 5 has one value
/// in each of the `2^k` intervals of [0, 1), whatever the tracking draws
/// of the steps before.
#[test]
fn march_steps_are_stratified_whatever_came_before() {
    let k = 8;
    let mut first_collision = vec![0u32; 1 << k];
    let points: Vec<Vec2> = (0..1u64 << k)
        .map(|s| {
            let mut sampler = PixelSampler::for_pixel(SamplerKind::Sobol, 3, 1, 4, s);
            let _pixel = sampler.next_2d();
            sampler.set_layout_block(Some(2));
            enter(&mut sampler, SCATTER_JITTER);
            let _ = sampler.next_1d();
            let mut light = Vec2::ZERO;
            for i in 0..8 {
                enter_march_step(&mut sampler, i, STEP_TRANSMITTANCE);
                if i == 5 {
                    first_collision[(sampler.next_1d() * (1 << k) as f32) as usize] += 1;
                }
                tracking(&mut sampler, s, 7 + i as u64, 12);
                enter_march_step(&mut sampler, i, STEP_LIGHT_POINT);
                let u = sampler.next_2d();
                if i == 5 {
                    light = u;
                }
                tracking(&mut sampler, s, 30 + i as u64, 4);
            }
            light
        })
        .collect();
    assert_eq!(bad_intervals(&points, k), 0);
    assert!(first_collision.iter().all(|&c| c == 1), "{first_collision:?}");
}

/// A slot's numbers are the Sobol sequence's at the slot's dimensions
/// (the draw-order sampler's numbers there), and without a walk step
/// entering a slot changes nothing (walks without the layout keep their
/// numbers bit for bit).
#[test]
fn slots_take_their_dimensions_and_need_a_walk_step() {
    let mut a = PixelSampler::for_pixel(SamplerKind::Sobol, 4, 1, 1, 17);
    a.set_layout_block(Some(2));
    enter(&mut a, LIGHT_POINT);
    let mut c = PixelSampler::for_pixel(SamplerKind::SobolSequential, 4, 1, 1, 17);
    for _ in 0..start(2, LIGHT_POINT) {
        c.next_1d();
    }
    assert_eq!(a.next_2d(), c.next_2d());

    let mut b = PixelSampler::for_pixel(SamplerKind::Sobol, 4, 1, 1, 17);
    let mut d = b.clone();
    enter(&mut b, LIGHT_POINT);
    enter_march_step(&mut b, 3, STEP_LIGHT_POINT);
    assert_eq!((b.next_2d(), b.next_1d()), (d.next_2d(), d.next_1d()));
    // Draw-order and independent samplers ignore the slots.
    for kind in [SamplerKind::SobolSequential, SamplerKind::Independent] {
        let mut e = PixelSampler::for_pixel(kind, 4, 1, 1, 17);
        let mut f = e.clone();
        e.set_layout_block(Some(1));
        enter(&mut e, SURFACE_LIGHT_POINT);
        assert_eq!(e.next_2d(), f.next_2d());
    }
}

/// Numbers past the slots are uniform and differ between samples: mean
/// 1/2 and variance 1/12 over 4096 samples of one pixel (standard errors
/// 4.5e-3 and 1.3e-3, bounds at 5 of them) for the tracking numbers after a
/// slot, a walk step beyond the laid-out ones and a march step beyond
/// [`MARCH_STEPS`].
#[test]
fn numbers_beyond_slots_are_uniform() {
    type Case = fn(&mut PixelSampler);
    let cases: [(&str, Case); 3] = [
        ("after a slot", |s| {
            s.set_layout_block(Some(0));
            enter(s, DISTANCE);
            for _ in 0..4 {
                s.next_1d();
            }
        }),
        ("late walk step", |s| {
            s.set_layout_block(Some(LAID_OUT_STEPS + 2));
            enter(s, LIGHT_POINT);
        }),
        ("late march step", |s| {
            s.set_layout_block(Some(1));
            enter_march_step(s, MARCH_STEPS + 7, STEP_LIGHT_POINT);
        }),
    ];
    for (name, prepare) in cases {
        let v: Vec<f64> = (0..4096u64)
            .map(|i| {
                let mut sampler = PixelSampler::for_pixel(SamplerKind::Sobol, 1, 2, 3, i);
                prepare(&mut sampler);
                sampler.next_1d() as f64
            })
            .collect();
        let n = v.len() as f64;
        let mean = v.iter().sum::<f64>() / n;
        let var = v.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / n;
        assert!((mean - 0.5).abs() < 5.0 * 4.5e-3, "{name}: mean {mean}");
        assert!((var - 1.0 / 12.0).abs() < 5.0 * 1.3e-3, "{name}: variance {var}");
    }
}

/// Independent numbers of different late steps, and of different march
/// steps, are not the same numbers.
#[test]
fn late_steps_draw_their_own_numbers() {
    let draw = |block: u32, march: Option<u32>| {
        let mut s = PixelSampler::for_pixel(SamplerKind::Sobol, 1, 2, 3, 5);
        s.set_layout_block(Some(block));
        match march {
            Some(i) => enter_march_step(&mut s, i, STEP_LIGHT_POINT),
            None => enter(&mut s, LIGHT_POINT),
        }
        s.next_2d()
    };
    assert_ne!(draw(LAID_OUT_STEPS, None), draw(LAID_OUT_STEPS + 1, None));
    assert_ne!(draw(LAID_OUT_STEPS, None), draw(0, None));
    assert_ne!(draw(0, Some(MARCH_STEPS)), draw(0, Some(MARCH_STEPS + 1)));
    assert_ne!(draw(0, Some(MARCH_STEPS)), draw(1, Some(MARCH_STEPS)));
}
