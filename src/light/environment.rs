//! Environment light (pbrt-v4 `ImageInfiniteLight` / `UniformInfiniteLight`, Mitsuba 3
//! `envmap` / `constant`): radiance arriving from infinitely far in every direction, from an
//! equirectangular image times `radiance`, or `radiance` alone.
//!
//! - **Mapping** (Mitsuba 3's, so references agree): a direction `d` toward the sky, in the
//!   light's own frame (`+Y` up), is at image column `u = atan2(d.x, -d.z) / 2π` (wrapped to
//!   `[0, 1)`) and row `t = acos(d.y) / π` from the top. The scene file's `rotate` turns the
//!   sky about the world.
//! - **Light samples** follow the image's luminance times `sin θ`, one texel at a time; the
//!   weights are the largest luminance of each texel's 3 × 3 neighbourhood (the bilinear
//!   lookup reaches that far), plus a floor, so every direction that has radiance can be
//!   sampled (photons, which only light sampling makes, would otherwise miss it).
//! - **Photons** leave a disc covering the scene's bounding sphere, as a distant light's do,
//!   along a direction drawn as the light samples are: flux `π R² ∫ L dω`.

use super::{EmissionSample, LightSample};
use crate::geometry::Aabb;
use crate::sampling::{
    sample_uniform_disk_concentric, sample_uniform_sphere, uniform_sphere_pdf, Distribution1D, Frame,
};
use crate::texture::{Texture, Wrap};
use glam::{Mat3, Vec2, Vec3};
use std::f32::consts::PI;
use std::sync::Arc;

/// An equirectangular image shared by the scene description and the light (compared by
/// identity; shown by its file and size).
#[derive(Clone)]
pub struct EnvironmentMap(pub Arc<Texture>);

impl std::fmt::Debug for EnvironmentMap {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{} ({}x{})", self.0.path.display(), self.0.width(), self.0.height())
    }
}

impl PartialEq for EnvironmentMap {
    fn eq(&self, other: &Self) -> bool {
        Arc::ptr_eq(&self.0, &other.0)
    }
}

/// The sampling distribution over an image's texels: rows by their sums, then the texel.
#[derive(Clone, Debug)]
struct TexelDistribution {
    rows: Distribution1D,
    columns: Vec<Distribution1D>,
    width: usize,
    height: usize,
}

impl TexelDistribution {
    fn new(map: &Texture) -> TexelDistribution {
        let (w, h) = (map.width() as usize, map.height() as usize);
        // Luminance at each texel centre, as the bilinear lookup gives it there.
        let mut lum = vec![0.0f32; w * h];
        for y in 0..h {
            for x in 0..w {
                let uv = Vec2::new((x as f32 + 0.5) / w as f32, 1.0 - (y as f32 + 0.5) / h as f32);
                lum[y * w + x] = super::luminance(map.sample(uv, Wrap::Repeat).truncate()).max(0.0);
            }
        }
        let mean = lum.iter().map(|&l| l as f64).sum::<f64>() / (w * h) as f64;
        let floor = (1e-3 * mean) as f32;
        let mut columns = Vec::with_capacity(h);
        let mut row_sums = Vec::with_capacity(h);
        for y in 0..h {
            let sin = (PI * (y as f32 + 0.5) / h as f32).sin();
            let weights: Vec<f32> = (0..w)
                .map(|x| {
                    let mut m = 0.0f32;
                    for dy in [-1i64, 0, 1] {
                        let yy = (y as i64 + dy).clamp(0, h as i64 - 1) as usize;
                        for dx in [-1i64, 0, 1] {
                            let xx = (x as i64 + dx).rem_euclid(w as i64) as usize;
                            m = m.max(lum[yy * w + xx]);
                        }
                    }
                    (m + floor) * sin
                })
                .collect();
            row_sums.push(weights.iter().sum());
            columns.push(Distribution1D::new(&weights));
        }
        TexelDistribution { rows: Distribution1D::new(&row_sums), columns, width: w, height: h }
    }

    /// A point of `[0, 1]²` (column, row from the top) and its density there.
    fn sample(&self, u: [f32; 2]) -> Option<(Vec2, f32)> {
        let (y, py, uy) = self.rows.sample(u[1])?;
        let (x, px, ux) = self.columns[y].sample(u[0])?;
        let p = Vec2::new((x as f32 + ux) / self.width as f32, (y as f32 + uy) / self.height as f32);
        Some((p, px * py * (self.width * self.height) as f32))
    }

    /// The density at a point of `[0, 1]²`.
    fn pdf(&self, p: Vec2) -> f32 {
        let x = ((p.x * self.width as f32) as usize).min(self.width - 1);
        let y = ((p.y * self.height as f32) as usize).min(self.height - 1);
        self.rows.pmf(y) * self.columns[y].pmf(x) * (self.width * self.height) as f32
    }
}

/// Radiance from every direction at infinity.
#[derive(Clone, Debug)]
pub struct EnvironmentLight {
    /// Radiance (W m⁻² sr⁻¹), or the factor the map is multiplied by.
    pub radiance: Vec3,
    map: Option<(Arc<Texture>, TexelDistribution)>,
    /// The light's frame in the world (a rotation) and its inverse.
    to_world: Mat3,
    to_local: Mat3,
    scene_center: Vec3,
    scene_radius: f32,
    /// `∫ L dω` per channel.
    integral: Vec3,
}

/// Direction (light frame, unit) to image coordinates (column, row from the top), Mitsuba's.
#[inline]
fn to_image(d: Vec3) -> Vec2 {
    let mut u = d.x.atan2(-d.z) * (0.5 / PI);
    if u < 0.0 {
        u += 1.0;
    }
    Vec2::new(u, d.y.clamp(-1.0, 1.0).acos() / PI)
}

/// Image coordinates to the direction (light frame), and `sin θ`.
#[inline]
fn from_image(p: Vec2) -> (Vec3, f32) {
    let (phi, theta) = (2.0 * PI * p.x, PI * p.y);
    let (sin_t, cos_t) = theta.sin_cos();
    (Vec3::new(sin_t * phi.sin(), cos_t, -sin_t * phi.cos()), sin_t)
}

/// `∫ L dω` of an equirectangular image as [`EnvironmentLight::radiance_toward`] looks it up,
/// exactly: along a row the bilinear lookup (wrapping) integrates to the mean of the rows it
/// blends, and between two rows' centres it is linear in the row coordinate `y`, against
/// `dω = 2π² sin(πy) dx dy`; above the first centre and below the last it is that row's.
fn bilinear_integral(t: &Texture) -> Vec3 {
    use std::f64::consts::PI;
    let (w, h) = (t.width() as usize, t.height() as usize);
    let rows: Vec<glam::DVec3> = (0..h)
        .map(|y| {
            let v = 1.0 - (y as f32 + 0.5) / h as f32;
            (0..w)
                .map(|x| {
                    t.sample(Vec2::new((x as f32 + 0.5) / w as f32, v), Wrap::Repeat).truncate().as_dvec3()
                })
                .sum::<glam::DVec3>()
                / w as f64
        })
        .collect();
    // ∫ sin(πy) dy and ∫ y sin(πy) dy.
    let i0 = |y: f64| -(PI * y).cos() / PI;
    let i1 = |y: f64| -y * (PI * y).cos() / PI + (PI * y).sin() / (PI * PI);
    let centre = |j: usize| (j as f64 + 0.5) / h as f64;
    let mut sum = rows[0] * (i0(centre(0)) - i0(0.0)) + rows[h - 1] * (i0(1.0) - i0(centre(h - 1)));
    for j in 0..h - 1 {
        let (a, b) = (centre(j), centre(j + 1));
        let whole = i0(b) - i0(a);
        let rising = (i1(b) - i1(a) - a * whole) / (b - a);
        sum += rows[j] * (whole - rising) + rows[j + 1] * rising;
    }
    (sum * 2.0 * PI * PI).as_vec3()
}

impl EnvironmentLight {
    /// A sky of `radiance` times `map` (if any), turned by `to_world`; no power until
    /// [`EnvironmentLight::preprocess`].
    pub fn new(radiance: Vec3, map: Option<Arc<Texture>>, to_world: Mat3) -> Self {
        let map = map.map(|t| {
            let d = TexelDistribution::new(&t);
            (t, d)
        });
        let integral = match &map {
            None => 4.0 * PI * radiance,
            Some((t, _)) => bilinear_integral(t) * radiance,
        };
        EnvironmentLight {
            radiance,
            map,
            to_world,
            to_local: to_world.transpose(),
            scene_center: Vec3::ZERO,
            scene_radius: 0.0,
            integral,
        }
    }

    /// Records the scene's bounding sphere (where photons come from).
    pub fn preprocess(&mut self, scene_bounds: Aabb) {
        (self.scene_center, self.scene_radius) =
            if scene_bounds.is_empty() { (Vec3::ZERO, 0.0) } else { scene_bounds.bounding_sphere() };
    }

    /// Radiance arriving along `-w` from the sky in direction `w` (world, unit).
    #[inline]
    pub fn radiance_toward(&self, w: Vec3) -> Vec3 {
        match &self.map {
            None => self.radiance,
            Some((t, _)) => {
                let p = to_image(self.to_local * w);
                self.radiance * t.sample(Vec2::new(p.x, 1.0 - p.y), Wrap::Repeat).truncate()
            }
        }
    }

    /// Solid-angle density of [`EnvironmentLight::sample_li`] for direction `w` (world).
    #[inline]
    pub fn pdf(&self, w: Vec3) -> f32 {
        match &self.map {
            None => uniform_sphere_pdf(),
            Some((_, dist)) => {
                let d = self.to_local * w;
                let sin = (1.0 - d.y * d.y).max(0.0).sqrt();
                if sin <= 0.0 {
                    return 0.0;
                }
                dist.pdf(to_image(d)) / (2.0 * PI * PI * sin)
            }
        }
    }

    /// A direction toward the sky (world) and its solid-angle density.
    #[inline]
    fn sample_direction(&self, u: [f32; 2]) -> Option<(Vec3, f32)> {
        match &self.map {
            None => Some((sample_uniform_sphere(u), uniform_sphere_pdf())),
            Some((_, dist)) => {
                let (p, pdf) = dist.sample(u)?;
                // Off the poles themselves, where the density per solid angle is infinite.
                let p = Vec2::new(p.x, p.y.clamp(1e-6, 1.0 - 1e-6));
                let (d, sin) = from_image(p);
                if sin <= 0.0 {
                    return None;
                }
                Some((self.to_world * d, pdf / (2.0 * PI * PI * sin)))
            }
        }
    }

    /// `π R² ∫ L dω`: the flux through the disc photons start from.
    pub fn power(&self) -> Vec3 {
        self.integral * PI * self.scene_radius * self.scene_radius
    }

    /// A direction toward the sky from anywhere, by the light's distribution.
    pub fn sample_li(&self, u: [f32; 2]) -> Option<LightSample> {
        let (wi, pdf) = self.sample_direction(u)?;
        let li = self.radiance_toward(wi);
        (pdf > 0.0).then_some(LightSample { wi, dist: f32::INFINITY, end_error: 0.0, li, pdf, delta: false })
    }

    /// A photon: a direction from the sky by its distribution (`u_dir`), travelling inward from
    /// a uniform point (`u_pos`) of the disc across the scene's bounding sphere, outside it.
    pub fn sample_emission(&self, u_pos: [f32; 2], u_dir: [f32; 2]) -> Option<EmissionSample> {
        let r = self.scene_radius;
        if r <= 0.0 || !r.is_finite() {
            return None;
        }
        let (w, pdf_dir) = self.sample_direction(u_dir)?;
        let dir = -w;
        let frame = Frame::from_z(dir);
        let d = sample_uniform_disk_concentric(u_pos) * r;
        let back = r * 1.001 + 1e-4;
        Some(EmissionSample {
            ray_origin: self.scene_center + frame.from_local(Vec3::new(d.x, d.y, -back)),
            dir,
            normal: None,
            pdf_pos: 1.0 / (PI * r * r),
            pdf_dir,
            le: self.radiance_toward(w),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec4;
    use std::path::Path;

    /// A 16 × 8 sky, dark but for a bright 2 × 1 patch and a dim band.
    fn sky() -> Arc<Texture> {
        let (w, h) = (16u32, 8u32);
        let texels = (0..w * h)
            .map(|i| {
                let (x, y) = (i % w, i / w);
                let v = if (5..7).contains(&x) && y == 2 {
                    50.0
                } else if y == 5 {
                    0.5
                } else {
                    0.0
                };
                Vec4::new(v, v * 0.5, v * 0.25, 1.0)
            })
            .collect();
        Arc::new(Texture::from_linear(Path::new("sky"), w, h, texels))
    }

    #[test]
    fn the_mapping_is_mitsubas_and_inverts() {
        // -Z is the image's centre column... u = atan2(0, 1) = 0: the left edge; +X a quarter in.
        assert!((to_image(Vec3::NEG_Z) - Vec2::new(0.0, 0.5)).length() < 1e-6);
        assert!((to_image(Vec3::X) - Vec2::new(0.25, 0.5)).length() < 1e-6);
        assert!((to_image(Vec3::Y).y).abs() < 1e-6);
        for i in 0..100 {
            let p = Vec2::new((i as f32 * 0.618_034).fract(), 0.02 + 0.96 * (i as f32 + 0.5) / 100.0);
            let (d, _) = from_image(p);
            assert!((to_image(d) - p).length() < 1e-4, "{p} -> {d} -> {}", to_image(d));
        }
    }

    #[test]
    fn samples_follow_the_pdf_and_the_power_is_the_integral() {
        let rot = Mat3::from_axis_angle(Vec3::new(0.3, 1.0, 0.2).normalize(), 0.7);
        let mut l = EnvironmentLight::new(Vec3::new(1.0, 2.0, 1.0), Some(sky()), rot);
        l.preprocess(Aabb::from_points([Vec3::ZERO, Vec3::ONE]));
        // E[L / pdf] over light samples is ∫ L dω; so is a uniform-sphere estimate.
        let (n, mut by_light, mut by_sphere, mut mismatched) = (200_000, Vec3::ZERO, Vec3::ZERO, 0);
        for i in 0..n {
            let u = [((i as f32) + 0.5) / n as f32, (i as f64 * 0.754_877_666_246_692_7).fract() as f32];
            let s = l.sample_li(u).unwrap();
            // Equal but on a texel's edge, where rounding may put the direction next door.
            mismatched += usize::from((s.pdf - l.pdf(s.wi)).abs() > 2e-3 * s.pdf);
            by_light += s.li / s.pdf / n as f32;
            let w = sample_uniform_sphere(u);
            by_sphere += l.radiance_toward(w) / uniform_sphere_pdf() / n as f32;
        }
        assert!(mismatched < n / 1000, "{mismatched} samples whose pdf is not pdf()'s");
        for c in 0..3 {
            assert!((by_light[c] / l.integral[c] - 1.0).abs() < 0.01, "{by_light} vs {}", l.integral);
            assert!((by_sphere[c] / l.integral[c] - 1.0).abs() < 0.05, "{by_sphere} vs {}", l.integral);
        }
        let (_, r) = Aabb::from_points([Vec3::ZERO, Vec3::ONE]).bounding_sphere();
        assert!((l.power() - l.integral * PI * r * r).abs().max_element() < 1e-3);
        // A photon's power, averaged, is the light's power.
        let mut flux = Vec3::ZERO;
        for i in 0..n {
            let u = [((i as f32) + 0.5) / n as f32, (i as f64 * 0.754_877_666_246_692_7).fract() as f32];
            flux += l
                .sample_emission([(i as f64 * 0.569_840_290_998_053_3).fract() as f32, 0.5], u)
                .unwrap()
                .photon_power()
                / n as f32;
        }
        assert!((flux / l.power() - Vec3::ONE).abs().max_element() < 0.01, "{flux} vs {}", l.power());
    }

    #[test]
    fn a_constant_sky_is_uniform() {
        let mut l = EnvironmentLight::new(Vec3::splat(2.0), None, Mat3::IDENTITY);
        l.preprocess(Aabb::from_points([Vec3::ZERO, Vec3::ONE]));
        assert_eq!(l.radiance_toward(Vec3::X), Vec3::splat(2.0));
        assert_eq!(l.pdf(Vec3::Y), uniform_sphere_pdf());
        assert!((l.integral - Vec3::splat(8.0 * PI)).abs().max_element() < 1e-4);
    }
}
