//! A material at a surface point with two normals: the triangle's geometric normal, which
//! decides sides (which way light leaves, where a ray starts, which photons a gather takes), and
//! the shading normal interpolated from vertex normals, which the BSDF is evaluated about
//! (Veach 1997, §5.3). For a flat triangle the two are the same and every function here reduces
//! to the plain [`Material`] one.
//!
//! - The BSDF's lobe is taken about the shading normal, as pbrt-v4 and Mitsuba 3 do, so a
//!   low-poly sphere's terminator follows the smooth normals, not the facets (rays that leave on
//!   the shading side start from the lifted point of [`SurfaceHit`](crate::frame::SurfaceHit),
//!   Hanika 2021, so the facet's neighbours do not shadow it).
//! - The geometry still decides where light goes: the part of a reflection lobe that falls
//!   behind the face is *folded* back in front of it (mirrored about the face's plane), and
//!   light from behind the face reflects nothing. So no light leaks through a surface however
//!   its normals lean, and a Lambertian surface still reflects exactly `kd` of what falls on
//!   it (a white furnace made of smooth-shaded triangles keeps its exact answer). Transmission
//!   is folded the same way, to the far side.
//! - Where the viewer sees the face from one side but the shading normal from the other (a
//!   grazing view at a silhouette), the point is shaded flat: the lobe would be inside the
//!   object.
//! - Camera paths (radiance) weigh a sample by `f |wi · ns| / pdf`.
//! - Photons (importance) are scattered with the adjoint BSDF, which with shading normals is
//!   not the same one: their weight has the extra factor `|wo · ns| |wi · ng| / (|wo · ng|
//!   |wi · ns|)` (Veach, eq. 5.19).
//! - Gathers weigh each photon by the BSDF alone, over the geometric area the photons landed
//!   on, as pbrt-v4's SPPM does: Veach's further factor `|wp · ns| / |wp · ng|` per photon has
//!   unbounded variance for photons grazing the face, and averages to one for a Lambertian
//!   surface lit evenly.

use super::{BsdfSample, LobeKind, Material, PhotonScatter, TransportMode};
use glam::Vec3;

/// The normals of a surface point: `geometric` (the triangle's, front as wound) and `shading`
/// (on the geometric front side; equal to it for flat shading). Both unit.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Normals {
    pub geometric: Vec3,
    pub shading: Vec3,
    /// Whether rays leaving on the shading side start from a point lifted off the face (see
    /// [`SurfaceHit::lifted`](crate::frame::SurfaceHit)): then light from just behind the face
    /// but in front of the shading normal is light the smooth surface faces, and the shadow
    /// ray from the lifted point decides whether it arrives.
    pub lifted: bool,
    /// Whether `shading` differs from `geometric` (the flat case takes no detours).
    pub bent: bool,
}

/// A sampled direction and the throughput factor it carries.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Scattered {
    pub sample: BsdfSample,
    /// `f |cos| / pdf`, with the adjoint factor for [`TransportMode::Importance`].
    pub weight: Vec3,
}

impl Normals {
    /// A flat-shaded point.
    #[inline]
    pub fn flat(n: Vec3) -> Normals {
        Normals { geometric: n, shading: n, lifted: false, bent: false }
    }

    /// The normals of a point (`bent` worked out here).
    #[inline]
    pub fn new(geometric: Vec3, shading: Vec3, lifted: bool) -> Normals {
        Normals { geometric, shading, lifted, bent: shading != geometric }
    }

    /// The normal the BSDF is taken about for a path arriving from `wo`: the shading normal,
    /// unless `wo` is on opposite sides of it and of the face (then the geometric one).
    #[inline]
    pub fn about(&self, wo: Vec3) -> Vec3 {
        if !self.bent {
            return self.geometric;
        }
        if self.shading.dot(wo) * self.geometric.dot(wo) > 0.0 {
            self.shading
        } else {
            self.geometric
        }
    }

    /// `w` mirrored about the face's plane.
    #[inline]
    fn mirrored(&self, w: Vec3) -> Vec3 {
        w - 2.0 * self.geometric.dot(w) * self.geometric
    }

    /// Reflected radiance per unit incident radiance from `wi` toward `wo`: the non-delta BSDF
    /// times the cosine, `f(wi) |wi · n| + f(wi') |wi' · n|` with `wi'` the mirror image of
    /// `wi` behind the face (the lobe's folded part). For `wi` behind the face, `f(wi) |wi · n|`
    /// on a lifted point (the smooth surface's terminator) and zero elsewhere: only a shadow
    /// ray from the lifted point can tell a light the smooth surface faces from one behind a
    /// wall. Light samples use this; the BSDF's samples never go behind the face.
    #[inline]
    pub fn eval_cos(&self, m: &Material, wo: Vec3, wi: Vec3) -> Vec3 {
        let (f, cos) = self.eval_parts(m, wo, wi);
        f * cos
    }

    /// [`Normals::eval_cos`] as a BSDF value and a cosine, `(f(wi), |wi · n|)` on a flat
    /// point (so callers multiply in the same order as without shading normals) and
    /// `(eval_cos, 1)` on a smooth one.
    #[inline]
    pub fn eval_parts(&self, m: &Material, wo: Vec3, wi: Vec3) -> (Vec3, f32) {
        if !self.bent {
            let n = self.geometric;
            if n.dot(wo) * n.dot(wi) <= 0.0 {
                return (Vec3::ZERO, 0.0);
            }
            return (m.eval(n, wo, wi), n.dot(wi).abs());
        }
        let n = self.about(wo);
        if self.geometric.dot(wo) * self.geometric.dot(wi) <= 0.0 {
            if self.lifted && n != self.geometric && n.dot(wi) * n.dot(wo) > 0.0 {
                return (m.eval(n, wo, wi) * n.dot(wi).abs(), 1.0);
            }
            return (Vec3::ZERO, 0.0);
        }
        if n == self.geometric {
            return (m.eval(n, wo, wi), n.dot(wi).abs());
        }
        let w = self.mirrored(wi);
        (m.eval(n, wo, wi) * n.dot(wi).abs() + m.eval(n, wo, w) * n.dot(w).abs(), 1.0)
    }

    /// The density [`Normals::sample`] gives `wi` (its folded part included).
    #[inline]
    pub fn pdf(&self, m: &Material, wo: Vec3, wi: Vec3) -> f32 {
        if self.geometric.dot(wo) * self.geometric.dot(wi) <= 0.0 {
            return 0.0;
        }
        let n = self.about(wo);
        if n == self.geometric {
            return m.pdf(n, wo, wi);
        }
        m.pdf(n, wo, wi) + m.pdf(n, wo, self.mirrored(wi))
    }

    /// What [`Normals::gather_eval`] gives every photon in front of the face, where that does
    /// not depend on the photon's direction (a Lambertian lobe about an unbent normal): a gather
    /// then weighs by it without evaluating the BSDF per photon.
    #[inline]
    pub fn gather_constant(&self, m: &Material, wo: Vec3) -> Option<Vec3> {
        match *m {
            Material::Diffuse { kd } | Material::Emissive { kd, .. }
                if !self.bent && self.geometric.dot(wo) != 0.0 =>
            {
                Some(kd * std::f32::consts::FRAC_1_PI)
            }
            _ => None,
        }
    }

    /// The BSDF a gather weighs a photon arriving from `wp` by (`wp` in front of the face): the
    /// lobe's value at `wp`, or at its mirror image where `wp` is below the shading normal.
    #[inline]
    pub fn gather_eval(&self, m: &Material, wo: Vec3, wp: Vec3) -> Vec3 {
        let n = self.about(wo);
        let w = if n.dot(wp) * n.dot(wo) >= 0.0 { wp } else { self.mirrored(wp) };
        m.eval(n, wo, w)
    }

    /// Samples `wi` and its throughput factor; the part of the lobe behind the face (in front
    /// of it, for a transmission) is folded over.
    #[inline]
    pub fn sample(
        &self,
        m: &Material,
        wo: Vec3,
        u_lobe: f32,
        u: [f32; 2],
        mode: TransportMode,
    ) -> Option<Scattered> {
        let n = self.about(wo);
        let mut s = m.sample_mode(n, wo, u_lobe, u, mode)?;
        let mut weight = s.weight(n);
        if self.bent && n != self.geometric {
            if mode == TransportMode::Importance {
                let adjoint = (wo.dot(n) * s.wi.dot(self.geometric)) / (wo.dot(self.geometric) * s.wi.dot(n));
                weight *= adjoint.abs();
            }
            let across = self.geometric.dot(wo) * self.geometric.dot(s.wi) < 0.0;
            if across != (s.kind == LobeKind::SpecularTransmission) {
                s.wi = self.mirrored(s.wi);
            }
            if !s.delta {
                // The value and density of the direction as folded, as `eval_cos` and `pdf`
                // give them (the weight above is their ratio already).
                s.pdf = self.pdf(m, wo, s.wi);
                s.f = self.eval_cos(m, wo, s.wi) / n.dot(s.wi).abs();
            }
        }
        (weight.is_finite() && s.wi.is_finite()).then_some(Scattered { sample: s, weight })
    }

    /// One photon bounce with Russian roulette ([`Material::photon_probabilities`], Jensen 2001
    /// §5.2): `u_rr` decides diffuse-like / specular / absorbed, the survivor is scattered by
    /// the adjoint BSDF and its power divided by the survival probability, so the estimate
    /// stays unbiased (exactly `power` for a grey Lambertian flat surface with `Some(ch)`).
    /// `None`: absorbed (or no sample).
    #[allow(clippy::too_many_arguments)]
    pub fn scatter_photon(
        &self,
        m: &Material,
        wo: Vec3,
        power: Vec3,
        channel: Option<usize>,
        u_rr: f32,
        u_lobe: f32,
        u: [f32; 2],
    ) -> Option<PhotonScatter> {
        let (p_d, p_s) = m.photon_probabilities(channel);
        let p = if u_rr < p_d {
            p_d
        } else if u_rr < p_d + p_s {
            p_s
        } else {
            return None;
        };
        let s = self.sample(m, wo, u_lobe, u, TransportMode::Importance)?;
        let power = power * s.weight / p;
        (power.is_finite() && power.max_element() > 0.0).then_some(PhotonScatter {
            wi: s.sample.wi,
            power,
            kind: s.sample.kind,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tilted() -> Normals {
        Normals::new(Vec3::Z, Vec3::new(0.3, 0.0, 1.0).normalize(), false)
    }

    /// xorshift uniforms for the sampling checks.
    fn uniforms(seed: u32) -> impl FnMut() -> f32 {
        let mut x = seed;
        move || {
            x ^= x << 13;
            x ^= x >> 17;
            x ^= x << 5;
            (x >> 8) as f32 / (1u32 << 24) as f32
        }
    }

    #[test]
    fn flat_shading_is_the_plain_material() {
        let m = Material::Glossy { kd: Vec3::splat(0.3), ks: Vec3::splat(0.4), ns: 30.0 };
        let n = Normals::flat(Vec3::Z);
        let wo = Vec3::new(0.2, 0.1, 0.9).normalize();
        let wi = Vec3::new(-0.4, 0.3, 0.7).normalize();
        assert_eq!(n.eval_cos(&m, wo, wi), m.eval(Vec3::Z, wo, wi) * wi.z);
        assert_eq!(n.gather_eval(&m, wo, wi), m.eval(Vec3::Z, wo, wi));
        assert_eq!(n.pdf(&m, wo, wi), m.pdf(Vec3::Z, wo, wi));
        for mode in [TransportMode::Radiance, TransportMode::Importance] {
            let s = n.sample(&m, wo, 0.7, [0.3, 0.6], mode).unwrap();
            let plain = m.sample_mode(Vec3::Z, wo, 0.7, [0.3, 0.6], mode).unwrap();
            assert_eq!(s.sample, plain);
            assert_eq!(s.weight, plain.weight(Vec3::Z));
        }
    }

    /// The gather's constant is `gather_eval` bit for bit for every photon in front of the
    /// face, on either side; there is none for a glossy lobe or a bent normal.
    #[test]
    fn a_lambertian_gather_weighs_every_photon_alike() {
        let m = Material::Diffuse { kd: Vec3::new(0.3, 0.5, 0.7) };
        let mut u = uniforms(9);
        let mut dir = || Vec3::new(u() - 0.5, u() - 0.5, u() - 0.5).normalize();
        for n in [Normals::flat(Vec3::Z), Normals::flat(Vec3::new(0.6, 0.0, -0.8))] {
            for _ in 0..1000 {
                let (wo, wp) = (dir(), dir());
                let front = if n.geometric.dot(wo) > 0.0 { n.geometric } else { -n.geometric };
                if wp.dot(front) <= 0.0 {
                    continue;
                }
                assert_eq!(n.gather_constant(&m, wo), Some(n.gather_eval(&m, wo, wp)));
            }
        }
        let glossy = Material::Glossy { kd: Vec3::splat(0.3), ks: Vec3::splat(0.4), ns: 30.0 };
        assert_eq!(Normals::flat(Vec3::Z).gather_constant(&glossy, Vec3::Z), None);
        assert_eq!(tilted().gather_constant(&m, Vec3::Z), None);
    }

    #[test]
    fn the_shading_normal_decides_the_lobe_except_at_a_silhouette() {
        let m = Material::Diffuse { kd: Vec3::splat(0.8) };
        let n = tilted();
        // Just above the face and far off the shading normal: the folded lobe adds to it.
        let wo = Vec3::new(0.5, 0.0, 0.5).normalize();
        let wi = Vec3::new(-0.99, 0.0, 0.1).normalize();
        assert!(n.shading.dot(wi) < 0.0 && n.geometric.dot(wi) > 0.0);
        let folded = Vec3::new(wi.x, wi.y, -wi.z);
        assert_eq!(n.eval_cos(&m, wo, wi), m.eval(n.shading, wo, folded) * n.shading.dot(folded));
        // Behind the face: nothing, however the shading normal leans.
        let below = Vec3::new(0.99, 0.0, -0.1).normalize();
        assert!(n.shading.dot(below) > 0.0);
        assert_eq!(n.eval_cos(&m, wo, below), Vec3::ZERO);
        assert_eq!(n.pdf(&m, wo, below), 0.0);
        // ... unless the point is lifted off the face (a convex spot): then its shadow ray
        // decides, and the light counts as the smooth surface sees it.
        let lifted = Normals { lifted: true, ..n };
        assert_eq!(lifted.eval_cos(&m, wo, below), m.eval(n.shading, wo, below) * n.shading.dot(below));
        assert_eq!(lifted.pdf(&m, wo, below), 0.0);
        // Seen from above the face but from behind the shading normal: shaded flat.
        let grazing = Vec3::new(-0.99, 0.0, 0.1).normalize();
        assert!(n.shading.dot(grazing) < 0.0 && n.geometric.dot(grazing) > 0.0);
        assert_eq!(n.about(grazing), Vec3::Z);
        assert_eq!(n.eval_cos(&m, grazing, Vec3::Z), m.eval(Vec3::Z, grazing, Vec3::Z));
    }

    #[test]
    fn folding_keeps_samples_in_front_and_lambertian_energy_exact() {
        let m = Material::Diffuse { kd: Vec3::splat(0.8) };
        let n = tilted();
        let wo = Vec3::new(0.2, 0.3, 0.9).normalize();
        let mut u = uniforms(0x1234_5678);
        let (mut folded, count) = (0, 4000);
        for _ in 0..count {
            let (ul, u2) = (u(), [u(), u()]);
            for mode in [TransportMode::Radiance, TransportMode::Importance] {
                let s = n.sample(&m, wo, ul, u2, mode).unwrap();
                assert!(s.sample.wi.z > 0.0, "a sample behind the face: {:?}", s.sample.wi);
                if mode == TransportMode::Radiance {
                    // Exactly kd: nothing is lost to the part of the lobe behind the face.
                    assert!((s.weight.x - 0.8).abs() < 1e-5, "{}", s.weight.x);
                    // The sample's own value and density are those eval_cos and pdf give.
                    let (f, pdf) = (s.sample.f.x * n.shading.dot(s.sample.wi), s.sample.pdf);
                    assert!((f - n.eval_cos(&m, wo, s.sample.wi).x).abs() < 1e-5);
                    assert!((pdf - n.pdf(&m, wo, s.sample.wi)).abs() < 1e-4 * pdf.max(1.0));
                    let plain = m.sample_mode(n.shading, wo, ul, u2, mode).unwrap();
                    folded += usize::from(plain.wi.z < 0.0);
                }
            }
        }
        assert!(folded > 0, "the lobe reaches behind the face, so some samples are folded");
        // The folded density integrates to one over the front hemisphere (uniform sampling).
        let (mut sum, k) = (0.0f64, 200_000);
        for _ in 0..k {
            let (a, b) = (u(), u());
            let z = a;
            let r = (1.0 - z * z).max(0.0).sqrt();
            let phi = std::f32::consts::TAU * b;
            let w = Vec3::new(r * phi.cos(), r * phi.sin(), z);
            sum += n.pdf(&m, wo, w) as f64 * std::f64::consts::TAU / k as f64;
        }
        assert!((sum - 1.0).abs() < 0.01, "folded pdf integrates to {sum}");
    }

    #[test]
    fn photons_carry_the_adjoint_factor() {
        let m = Material::Diffuse { kd: Vec3::ONE };
        let n = tilted();
        let wo = Vec3::new(-0.2, 0.1, 0.8).normalize();
        assert_eq!(n.about(wo), n.shading);
        let r = n.sample(&m, wo, 0.5, [0.3, 0.4], TransportMode::Radiance).unwrap();
        let i = n.sample(&m, wo, 0.5, [0.3, 0.4], TransportMode::Importance).unwrap();
        assert_eq!(r.sample.wi, i.sample.wi);
        let wi = i.sample.wi;
        let expected = (wo.dot(n.shading) * wi.dot(Vec3::Z)) / (wo.dot(Vec3::Z) * wi.dot(n.shading));
        assert!((i.weight.x / r.weight.x - expected).abs() < 1e-5);
        assert!((expected - 1.0).abs() > 1e-3, "the case must bend something");
    }
}
