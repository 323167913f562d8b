//! Stochastic progressive photon mapping (Hachisuka & Jensen 2009), on the same kd-tree photon
//! maps as the two-pass method.
//!
//! Every pass traces fresh photon maps (the indirect map and, when the scene has mirrors or
//! glass, the aimed caustic map: together every photon path but the first hit, which direct
//! light covers) and `spp` camera samples per pixel. Emission and direct light (shadow rays)
//! along each sample are averaged over all passes. The first sample's first diffuse or glossy
//! hit is the pixel's *visible point* of the pass: the photons within the pixel's radius `R`
//! around it (a disc flattened along the surface, as in the gathers) give `M` photons and a
//! flux `Φ = Σ β f(wo, wi) power`, and the pixel's statistics are updated as in the paper:
//!
//! ```text
//! N' = N + α M,   R'² = R² N' / (N + M),   τ' = (τ + Φ) R'² / R²
//! ```
//!
//! After `n` passes the pixel is `Ld / n + τ / (n π R²)` (each photon's power is already its
//! pass's flux over the photons emitted in that pass). `R` starts at the distance to the
//! `k`-th nearest photon of the first visible point (`--gather-photons`, in the map where photons
//! are densest, so caustics start small), bounded by `--gather-radius`; it then shrinks so that
//! bias and variance both go to zero as passes are added.

use super::camera::{Scratch, SurfaceHit};
use super::direct::direct_light;
use super::{Counters, Progress, Shared};
use crate::accel::{Accel, Hit};
use crate::film::Film;
use crate::geometry::Ray;
use crate::material::{face_forward, Material};
use crate::photon::trace::mix;
use glam::Vec3;
use rand::{Rng, SeedableRng};
use rand_pcg::Pcg32;
use rayon::prelude::*;

/// A pixel's progressive statistics.
#[derive(Clone, Copy, Debug, Default)]
pub struct PixelState {
    /// Squared gather radius (0 until the first visible point).
    r2: f32,
    /// Accumulated photon count `N`.
    n: f32,
    /// Accumulated flux `τ`, scaled to the current radius.
    tau: Vec3,
    /// Sum over passes of the mean emission and direct light of the pass's samples.
    ld: Vec3,
}

/// The first diffuse or glossy surface a camera sample reaches.
struct Visible<'m> {
    hit: SurfaceHit,
    wo: Vec3,
    m: &'m Material,
    beta: Vec3,
}

/// One pass of the camera over every pixel, updating `states` (one per pixel, rows in
/// parallel; each pixel's generator comes from (seed, pixel), so the result does not depend on
/// the thread count).
pub fn camera_pass<A: Accel>(
    s: &Shared<'_, A>,
    states: &mut [PixelState],
    alpha: f32,
    progress: &dyn Progress,
) -> Counters {
    let w = s.cfg.width as usize;
    states
        .par_chunks_mut(w)
        .enumerate()
        .map_init(
            || {
                crate::accel::init_tracing_thread();
                Scratch::default()
            },
            |scratch, (y, row)| {
                let mut c = Counters::default();
                for (x, st) in row.iter_mut().enumerate() {
                    let pixel = (y * w + x) as u64;
                    let mut rng = Pcg32::seed_from_u64(mix(s.cfg.seed, 0xCA3E7A, pixel));
                    update_pixel(s, x as u32, y as u32, st, alpha, &mut rng, scratch, &mut c);
                }
                progress.advance(1);
                c
            },
        )
        .reduce(Counters::default, |mut a, b| {
            a += b;
            a
        })
}

/// The image after `passes` passes.
pub fn film(states: &[PixelState], width: usize, height: usize, passes: u32) -> Film {
    let mut film = Film::new(width, height);
    let n = passes.max(1) as f32;
    for (px, st) in film.pixels.iter_mut().zip(states) {
        let mut l = st.ld / n;
        if st.r2 > 0.0 {
            l += st.tau / (n * std::f32::consts::PI * st.r2);
        }
        *px = l;
    }
    film
}

#[allow(clippy::too_many_arguments)]
fn update_pixel<A: Accel>(
    s: &Shared<'_, A>,
    px: u32,
    py: u32,
    st: &mut PixelState,
    alpha: f32,
    rng: &mut Pcg32,
    scratch: &mut Scratch,
    c: &mut Counters,
) {
    let mut rays = std::mem::take(&mut scratch.rays);
    let mut hits = std::mem::take(&mut scratch.hits);
    s.camera_rays(px, py, &mut rays, &mut hits, c);
    let (mut sum, mut good) = (Vec3::ZERO, 0u32);
    let mut first = None;
    for (i, (ray, hit)) in rays.iter().zip(&hits).enumerate() {
        let (l, vis) = trace_camera(s, *ray, *hit, rng, c);
        if l.is_finite() {
            sum += l;
            good += 1;
        } else {
            c.nonfinite += 1;
        }
        if i == 0 {
            first = vis;
        }
    }
    scratch.rays = rays;
    scratch.hits = hits;
    if good > 0 {
        st.ld += sum / good as f32;
    }
    if let Some(v) = first {
        gather(s, st, &v, alpha, scratch, c);
    }
}

/// Follows a camera sample through mirrors and glass: returns the emission seen and the direct
/// light at the first diffuse or glossy surface, and that surface.
fn trace_camera<'s, A: Accel>(
    s: &'s Shared<'_, A>,
    mut ray: Ray,
    first: Option<Hit>,
    rng: &mut Pcg32,
    c: &mut Counters,
) -> (Vec3, Option<Visible<'s>>) {
    let mut beta = Vec3::ONE;
    let mut l = Vec3::ZERO;
    for depth in 0..=s.cfg.max_depth {
        let hit = if depth == 0 {
            first.and_then(|h| s.surface(h))
        } else {
            c.rays.specular += 1;
            s.trace(&ray)
        };
        let Some(hit) = hit else { break };
        let m = s.scene.material(hit.prim);
        let wo = -ray.dir.normalize();
        l += beta * m.emitted(hit.n, wo);
        if m.is_specular() {
            if depth == s.cfg.max_depth {
                break;
            }
            let Some(smp) = m.sample(hit.n, wo, rng.gen(), [rng.gen(), rng.gen()]) else { break };
            beta *= smp.weight(hit.n);
            if beta.max_element() <= 0.0 {
                break;
            }
            ray = Ray::new(hit.spawn(smp.wi), smp.wi);
            continue;
        }
        l += beta * direct_light(s, &hit, wo, m, s.cfg.light_samples, rng, c);
        return (l, Some(Visible { hit, wo, m, beta }));
    }
    (l, None)
}

/// The photons of this pass around the visible point: the progressive update of `st`.
fn gather<A: Accel>(
    s: &Shared<'_, A>,
    st: &mut PixelState,
    v: &Visible<'_>,
    alpha: f32,
    scratch: &mut Scratch,
    c: &mut Counters,
) {
    let maps = s.maps;
    if maps.indirect.is_empty() && maps.caustic.is_empty() {
        return;
    }
    let ns = face_forward(v.hit.n, v.wo);
    let x = v.hit.p;
    if st.r2 == 0.0 {
        // The first radius: the k-th nearest photon in the map where they are densest.
        let nb = &mut scratch.neighbors;
        let kinds = [(&maps.indirect, &s.gather), (&maps.caustic, &s.caustic_gather)];
        st.r2 = f32::INFINITY;
        for (kind, params) in kinds {
            for map in kind.iter() {
                st.r2 = st.r2.min(map.knn_radius2(x, ns, params, nb));
            }
        }
        c.queries += (maps.indirect.len() + maps.caustic.len()) as u64;
        if !(st.r2.is_finite() && st.r2 > 0.0) {
            st.r2 = 0.0;
            return;
        }
    }
    let r = st.r2.sqrt();
    let mut phi = Vec3::ZERO;
    let mut m = 0u32;
    for map in maps.indirect.iter().chain(&maps.caustic) {
        m += map.for_each_within(x, ns, r, s.gather.flatten, |wi, power| {
            phi += v.m.eval(v.hit.n, v.wo, wi) * power;
        });
    }
    c.queries += (maps.indirect.len() + maps.caustic.len()) as u64;
    let phi = v.beta * phi;
    if m == 0 {
        return;
    }
    if !phi.is_finite() {
        c.nonfinite += 1;
        return;
    }
    let (n, m) = (st.n, m as f32);
    let n_new = n + alpha * m;
    let ratio = n_new / (n + m);
    st.tau = (st.tau + phi) * ratio;
    st.r2 *= ratio;
    st.n = n_new;
}
