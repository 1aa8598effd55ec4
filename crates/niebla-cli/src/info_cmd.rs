//! `niebla info`: what a scene holds (camera, media, shapes, lights, render
//! settings), printed one item a line.

use std::path::Path;

use crate::error::CliError;

/// `niebla info`.
pub fn run(scene: Option<&Path>, defines: &[(String, String)]) -> Result<(), CliError> {
    if let Some(vdb) = scene.filter(|p| crate::info_vdb::is_vdb(p)) {
        return crate::info_vdb::run(vdb);
    }
    let (built, notes) = crate::load::load_defined(scene, defines)?;
    let s = &built.scene;
    let c = &s.camera;
    println!("scene: {}", scene.map_or("<default scene>".into(), |p| p.display().to_string()));
    println!(
        "camera: perspective at {:?} looking {:?}, {}x{} pixels, fov_y {:.1} deg",
        c.position.to_array(),
        c.forward.to_array(),
        c.width,
        c.height,
        2.0 * c.tan_half_fov_y.atan().to_degrees()
    );
    println!(
        "render: {}, {} spp, seed {}, exposure {}",
        built.settings.integrator.key(),
        built.settings.spp,
        built.settings.seed,
        built.settings.exposure
    );
    println!("media ({}):", s.media.len());
    for (name, m) in s.medium_names.iter().zip(&s.media) {
        match m.as_homogeneous() {
            Some(h) => println!(
                "  {name}: homogeneous, sigma_a {:?}, sigma_s {:?} (per unit length), L_ve {:?}, phase {} (mean cosine {:.3})",
                h.sigma_a.0,
                h.sigma_s.0,
                h.l_ve.0,
                h.phase.name(),
                h.phase.mean_cosine()
            ),
            None => {
                if let niebla::medium::Medium::Grid(g) = m {
                    let kind = match &g.density {
                        niebla::medium::DensityGrid::Dense(d) => format!("dense grid {:?} voxels", d.dims()),
                        niebla::medium::DensityGrid::Sparse(sp) => format!("sparse grid, {} leaves", sp.leaf_count()),
                    };
                    let emission = match &g.emission {
                        niebla::medium::GridEmission::None => "none".to_string(),
                        niebla::medium::GridEmission::ProportionalToDensity(l) => format!("L_ve {:?} x density", l.0),
                        niebla::medium::GridEmission::Field { scale, .. } => format!("grid x {:?}", scale.0),
                        niebla::medium::GridEmission::Temperature { scale, .. } => {
                            format!("blackbody of a temperature grid x {scale}")
                        }
                        niebla::medium::GridEmission::Pyro(e) => format!(
                            "pyro: {:?} x flame{}, blackbody intensity {} tint {:?}, T = {} x {} + {} K",
                            e.emission.0,
                            if e.flame.is_some() { " grid" } else { " 1 (no flame grid)" },
                            e.blackbody_intensity,
                            e.blackbody_tint.0,
                            e.temperature.scale,
                            if e.temperature.field.is_some() { "temperature grid" } else { "1" },
                            e.temperature.offset
                        ),
                    };
                    let albedo = match &g.albedo {
                        None => String::new(),
                        Some(a) => {
                            let (channels, dims) = match &a.grid {
                                niebla::medium::AlbedoGrid::Grey(d) => ("1 channel", d.dims()),
                                niebla::medium::AlbedoGrid::Rgb(d) => ("RGB", d.dims()),
                            };
                            format!(
                                ", albedo grid {dims:?} voxels ({channels}) x {:?}; sigma_s at grid albedo 1",
                                a.scale.0
                            )
                        }
                    };
                    println!(
                        "  {name}: grid medium, {kind}{albedo}, sigma_a {:?}, sigma_s {:?} per unit density, max \
                         sigma_t {:.3}, world bounds {:?}..{:?}, majorant grid {:?}, emission {emission}, phase {}",
                        g.sigma_a.0,
                        g.sigma_s.0,
                        g.max_sigma_t(),
                        g.world_bounds.0.to_array(),
                        g.world_bounds.1.to_array(),
                        g.majorant.res(),
                        g.phase.name()
                    );
                }
            }
        }
    }
    let name_of = |id: Option<niebla::medium::MediumId>| {
        id.map_or("vacuum".to_string(), |i| s.medium_names[i.0 as usize].clone())
    };
    println!("shapes ({}):", s.objects.len());
    for (i, o) in s.objects.iter().enumerate() {
        let (lo, hi) = o.shape.bounds();
        let kind = shape_kind(&o.shape);
        let media = if o.bounds_medium {
            format!(", interior {}, exterior {}", name_of(o.interior), name_of(o.exterior))
        } else {
            String::new()
        };
        let texture = match o.texture.as_deref() {
            Some(niebla::texture::Texture::Bitmap { image, .. }) => {
                format!(" with a {}x{} bitmap reflectance", image.width, image.height)
            }
            Some(niebla::texture::Texture::Checkerboard { .. }) => " with a checkerboard reflectance".to_string(),
            None => String::new(),
        };
        println!("  [{i}] {kind}, bounds {:?}..{:?}, bsdf {:?}{texture}{media}", lo.to_array(), hi.to_array(), o.bsdf);
    }
    println!("lights ({}):", s.lights.len());
    for (i, l) in s.lights.iter().enumerate() {
        println!("  [{i}] {l:?}");
    }
    println!("ambient medium: {}", name_of(s.ambient_medium));
    println!("camera medium: {}", name_of(s.camera_medium));
    if !notes.is_empty() {
        println!("accepted without effect ({}):", notes.len());
        for n in &notes {
            println!("  {n}");
        }
    }
    Ok(())
}

/// `x` with four decimals, without the sign of a value that rounds to zero
/// (so a rotation's zero entries print `0.0000`, not `-0.0000`).
fn fixed4(x: f32) -> String {
    let text = format!("{x:.4}");
    match text.strip_prefix('-') {
        Some(rest) if rest.bytes().all(|b| b == b'0' || b == b'.') => rest.to_string(),
        _ => text,
    }
}

/// How `niebla info` names a shape: its type, with a mesh's sizes and a
/// sphere's rotation (row-major, local to world) if it has one; a moving
/// shape as "moving" and its type (its bounds cover the shutter).
fn shape_kind(shape: &niebla::geometry::Shape) -> String {
    use niebla::geometry::Shape;
    match shape {
        Shape::Sphere(s) => match s.rotation {
            None => "sphere".to_string(),
            Some(r) => {
                let rows = (0..3)
                    .map(|i| {
                        let row = r.row(i);
                        format!("[{}, {}, {}]", fixed4(row.x), fixed4(row.y), fixed4(row.z))
                    })
                    .collect::<Vec<_>>();
                format!("sphere (uv frame turned by rotation [{}])", rows.join(", "))
            }
        },
        Shape::Box(_) => "box".to_string(),
        Shape::Rectangle(_) => "rectangle".to_string(),
        Shape::Disk(_) => "disk".to_string(),
        Shape::Mesh(m) => format!(
            "mesh ({} triangles, {} vertices{}, {} degenerate triangles skipped, {}, {})",
            m.mesh.triangle_count(),
            m.mesh.positions.len(),
            if m.mesh.normals.is_some() { " with normals" } else { "" },
            m.mesh.degenerate,
            if m.closed { "closed" } else { "open" },
            niebla::limits::format_bytes(m.mesh.memory_bytes() as u64)
        ),
        Shape::Moving(m) => format!("moving {} (bounds over the shutter)", shape_kind(&m.at_zero)),
    }
}

#[cfg(test)]
mod tests {
    use super::fixed4;

    #[test]
    fn values_that_round_to_zero_print_without_a_sign() {
        assert_eq!(fixed4(-0.0), "0.0000");
        assert_eq!(fixed4(-4e-5), "0.0000");
        assert_eq!(fixed4(-6e-5), "-0.0001");
        assert_eq!(fixed4(0.5), "0.5000");
        assert_eq!(fixed4(-1.0), "-1.0000");
    }
}
