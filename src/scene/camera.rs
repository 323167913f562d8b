//! The camera with the look-at convention of `scenes/SCENES.md` (Mitsuba's `perspective` with
//! `fov_axis = "y"`): a pinhole, or a thin lens (Mitsuba's `thinlens`, pbrt's `lensradius` and
//! `focaldistance`: Kolb, Mitchell and Hanrahan 1995, Pharr, Jakob and Humphreys, *PBR* 5.2.3),
//! and the scene's named cameras with their animation.
//!
//! A [`Camera`] is one view. A [`SceneCamera`] is a camera of the scene file: a name, its own
//! resolution, and a view per frame. It is still (one view for every frame), keyed (cubic
//! Hermite interpolation of [`CameraKey`]s in frame number, with the Catmull–Rom tangents of
//! non-uniform spacing, as in Catmull and Rom 1974 and the finite-difference "cardinal" form of
//! Kochanek and Bartels 1984 with zero tension), or a [`Turntable`] (the view turned about an
//! axis line). Every frame of an animation is checked when the camera is built, so
//! [`SceneCamera::view`] has no failure to report.

use crate::geometry::Ray;
use crate::sampling::sample_uniform_disk_concentric;
use glam::{DQuat, Vec3};
use std::ops::RangeInclusive;

/// Longest animation a camera may define, in frames (a keyed camera's first to last key, a
/// turntable's frame count): every frame is checked when the camera is built.
pub const MAX_FRAMES: u32 = 1_000_000;

/// A thin lens in front of the film: rays leave a disc of radius `aperture_radius` about the
/// eye, in the plane spanned by the camera's right and up vectors, and every ray of a film
/// position meets the pinhole ray of that position on the plane `focus_distance` in front of
/// the eye (perpendicular to the view direction). A radius of 0 is a pinhole.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Lens {
    /// Metres; 0 for a pinhole.
    pub aperture_radius: f32,
    /// Metres along the view direction from the eye to the plane in focus; positive.
    pub focus_distance: f32,
}

impl Lens {
    /// No lens: every ray leaves the eye.
    pub const PINHOLE: Lens = Lens { aperture_radius: 0.0, focus_distance: 1.0 };

    /// Whether the lens can be used: a finite radius `>= 0` and a finite focus distance `> 0`.
    pub fn is_valid(&self) -> bool {
        self.aperture_radius >= 0.0
            && self.aperture_radius.is_finite()
            && self.focus_distance > 0.0
            && self.focus_distance.is_finite()
    }

    /// Whether every ray leaves the eye.
    #[inline]
    pub fn is_pinhole(&self) -> bool {
        self.aperture_radius == 0.0
    }
}

/// A camera producing primary rays for film positions in pixels, through a pinhole or a thin
/// [`Lens`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    pub eye: Vec3,
    /// Unit forward, right and up vectors: `f = normalize(target - eye)`,
    /// `r = normalize(f x up)`, `u = r x f`.
    pub forward: Vec3,
    pub right: Vec3,
    pub up: Vec3,
    /// `tan(vfov / 2)`.
    pub tan_half_fov: f32,
    pub width: u32,
    pub height: u32,
    pub lens: Lens,
}

impl Camera {
    /// Builds a pinhole camera; `None` if the frame is degenerate (eye = target, up parallel to
    /// the view direction) or the field of view is not in (0, 180) degrees.
    pub fn look_at(
        eye: Vec3,
        target: Vec3,
        up: Vec3,
        vfov_deg: f32,
        width: u32,
        height: u32,
    ) -> Option<Self> {
        let forward = (target - eye).try_normalize()?;
        let right = forward.cross(up).try_normalize()?;
        let up = right.cross(forward);
        if !(vfov_deg > 0.0 && vfov_deg < 180.0) || width == 0 || height == 0 {
            return None;
        }
        let tan_half_fov = (0.5 * vfov_deg.to_radians()).tan();
        Some(Camera { eye, forward, right, up, tan_half_fov, width, height, lens: Lens::PINHOLE })
    }

    /// The same camera with another lens; `None` if `lens` is not [valid](Lens::is_valid).
    /// A pinhole is kept as [`Lens::PINHOLE`] whatever its focus distance (which changes
    /// nothing), so that equal views compare equal.
    pub fn with_lens(mut self, lens: Lens) -> Option<Self> {
        self.lens = if lens.is_pinhole() { Lens::PINHOLE } else { lens };
        lens.is_valid().then_some(self)
    }

    /// The direction from the eye through film position `(x, y)`, not normalised: its
    /// component along `forward` is 1.
    #[inline]
    fn film_direction(&self, x: f32, y: f32) -> Vec3 {
        let (w, h) = (self.width as f32, self.height as f32);
        let sx = (2.0 * x / w - 1.0) * self.tan_half_fov * (w / h);
        let sy = (1.0 - 2.0 * y / h) * self.tan_half_fov;
        self.forward + sx * self.right + sy * self.up
    }

    /// The pinhole ray from the eye (the centre of the lens) through film position `(x, y)` in
    /// pixels (`x` left to right in `[0, width)`, `y` top to bottom in `[0, height)`); the
    /// direction is normalised.
    #[inline]
    pub fn ray(&self, x: f32, y: f32) -> Ray {
        Ray::new(self.eye, self.film_direction(x, y).normalize())
    }

    /// The ray through film position `(x, y)` from the point of the lens that `lens` in
    /// `[0, 1)²` picks (Shirley and Chiu's concentric map onto the aperture's disc, as
    /// Mitsuba's `thinlens` samples it): it leaves that point towards where the pinhole ray
    /// meets the plane in focus. A pinhole gives [`Camera::ray`] bit for bit, whatever `lens`.
    #[inline]
    pub fn lens_ray(&self, x: f32, y: f32, lens: [f32; 2]) -> Ray {
        if self.lens.is_pinhole() {
            return self.ray(x, y);
        }
        let d = self.film_direction(x, y);
        let focus = self.eye + self.lens.focus_distance * d;
        let disc = self.lens.aperture_radius * sample_uniform_disk_concentric(lens);
        let origin = self.eye + disc.x * self.right + disc.y * self.up;
        Ray::new(origin, (focus - origin).normalize())
    }

    /// The diameter of the disc over which the lens blurs a point at `p` (the circle of
    /// confusion at `p`'s depth, in metres at that depth): `2 A |z - F| / F` for a point `z`
    /// along the view direction; 0 for a pinhole.
    pub fn defocus_diameter(&self, p: Vec3) -> f32 {
        if self.lens.is_pinhole() {
            return 0.0;
        }
        let z = (p - self.eye).dot(self.forward);
        2.0 * self.lens.aperture_radius * (z - self.lens.focus_distance).abs() / self.lens.focus_distance
    }

    /// The same camera at another resolution (the field of view is kept).
    pub fn with_resolution(mut self, width: u32, height: u32) -> Self {
        self.width = width;
        self.height = height;
        self
    }
}

/// What a camera key sets: the look-at frame, the vertical field of view and the lens.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CameraKey {
    pub eye: Vec3,
    pub target: Vec3,
    pub up: Vec3,
    pub vfov_deg: f32,
    pub lens: Lens,
}

/// How many numbers a key has that are interpolated.
const COMPONENTS: usize = 12;

impl CameraKey {
    /// The view at `width` x `height`; `None` where [`Camera::look_at`] refuses it, the field
    /// of view is so small that `tan(vfov / 2)` rounds to 0 (every pixel would get one ray), or
    /// the lens is not [valid](Lens::is_valid).
    pub fn view(&self, width: u32, height: u32) -> Option<Camera> {
        let c = Camera::look_at(self.eye, self.target, self.up, self.vfov_deg, width, height)?;
        (c.tan_half_fov > 0.0 && c.tan_half_fov.is_finite()).then_some(c)?.with_lens(self.lens)
    }

    /// The twelve numbers interpolated, in order: eye, target, up (x, y, z each), vfov_deg,
    /// aperture_radius, focus_distance.
    fn components(&self) -> [f64; COMPONENTS] {
        let (e, t, u, l) = (self.eye, self.target, self.up, self.lens);
        [e.x, e.y, e.z, t.x, t.y, t.z, u.x, u.y, u.z, self.vfov_deg, l.aperture_radius, l.focus_distance]
            .map(f64::from)
    }

    /// The key of interpolated numbers; the aperture's radius is clamped at 0 (the curve
    /// undershoots 0 next to a pinhole key whose neighbour opens the lens).
    fn from_components(c: [f64; COMPONENTS]) -> CameraKey {
        let v = |i: usize| Vec3::new(c[i] as f32, c[i + 1] as f32, c[i + 2] as f32);
        let lens = Lens { aperture_radius: (c[10] as f32).max(0.0), focus_distance: c[11] as f32 };
        CameraKey { eye: v(0), target: v(3), up: v(6), vfov_deg: c[9] as f32, lens }
    }
}

/// A turntable: the base view turned about the axis line through `center`, by
/// `degrees * f / frames` at frame `f` in `0..frames` (so `frames` frames of 360° loop without a
/// repeated frame). Turns are counter-clockwise seen from the tip of `axis` (right-hand rule):
/// about +Y, an eye on +Z moves toward +X.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Turntable {
    pub frames: u32,
    pub center: Vec3,
    /// Unit length.
    pub axis: Vec3,
    pub degrees: f32,
}

impl Turntable {
    /// `base` at frame `frame` (clamped to `0..frames`): eye and target turned about the axis
    /// line, up turned with them, the field of view and the lens kept. Frame 0 is `base` itself.
    fn turn(&self, base: &CameraKey, frame: u32) -> CameraKey {
        let f = frame.min(self.frames.saturating_sub(1));
        if f == 0 {
            return *base;
        }
        let angle = (f64::from(self.degrees) * f64::from(f) / f64::from(self.frames)).to_radians();
        let q = DQuat::from_axis_angle(self.axis.as_dvec3(), angle);
        let c = self.center.as_dvec3();
        let about = |p: Vec3| (c + q * (p.as_dvec3() - c)).as_vec3();
        CameraKey {
            eye: about(base.eye),
            target: about(base.target),
            up: (q * base.up.as_dvec3()).as_vec3(),
            vfov_deg: base.vfov_deg,
            lens: base.lens,
        }
    }
}

/// Why an animation was refused. [`MotionError::field`] names the part of the camera at fault.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum MotionError {
    #[error("{0} key given: an animation needs at least 2")]
    TooFewKeys(usize),
    #[error("frame {frame} does not come after the previous key's frame {previous}: key frames must increase strictly")]
    NotIncreasing { index: usize, frame: u32, previous: u32 },
    #[error("the animation spans {frames} frames, more than {MAX_FRAMES}")]
    TooManyFrames { turntable: bool, frames: u64 },
    #[error("a turntable of 0 frames: it needs at least 1")]
    NoFrames,
    #[error("the turntable's axis {0:?} is zero or not finite")]
    Axis([f32; 3]),
    #[error(
        "frame {frame}: the {} view is degenerate (eye equals target, up is parallel to the view \
         direction, the field of view is not in (0, 180), or the focus distance is not positive)",
        if *turntable { "turned" } else { "interpolated" }
    )]
    Degenerate { turntable: bool, frame: u32 },
}

impl MotionError {
    /// The field at fault, relative to the camera's table: `key`, `key[i].frame`,
    /// `turntable`, `turntable.frames` or `turntable.axis`.
    pub fn field(&self) -> String {
        let motion = |turntable: bool| if turntable { "turntable" } else { "key" };
        match self {
            MotionError::TooFewKeys(_) => "key".into(),
            MotionError::NotIncreasing { index, .. } => format!("key[{index}].frame"),
            MotionError::TooManyFrames { turntable: true, .. } | MotionError::NoFrames => {
                "turntable.frames".into()
            }
            MotionError::TooManyFrames { turntable, .. } | MotionError::Degenerate { turntable, .. } => {
                motion(*turntable).into()
            }
            MotionError::Axis(_) => "turntable.axis".into(),
        }
    }
}

/// How a scene camera's view changes with the frame.
#[derive(Clone, Debug, PartialEq)]
enum Motion {
    /// One view for every frame.
    Still(Camera),
    /// Keys with strictly increasing frames, at least 2.
    Keys(Vec<(u32, CameraKey)>),
    Turntable {
        base: CameraKey,
        turntable: Turntable,
    },
}

/// A camera of the scene file: a name (it goes into output file names), its own resolution, and
/// a view for every frame.
#[derive(Clone, Debug, PartialEq)]
pub struct SceneCamera {
    pub name: String,
    pub width: u32,
    pub height: u32,
    motion: Motion,
    /// Subtracted from the eye of every view: see [`SceneCamera::translated`].
    offset: Vec3,
}

impl SceneCamera {
    /// A still camera: `view` at every frame, at `view`'s resolution.
    pub fn still(name: impl Into<String>, view: Camera) -> SceneCamera {
        SceneCamera {
            name: name.into(),
            width: view.width,
            height: view.height,
            motion: Motion::Still(view),
            offset: Vec3::ZERO,
        }
    }

    /// A keyed camera: `keys` as (frame, key), frames strictly increasing, at least 2 of them,
    /// spanning at most [`MAX_FRAMES`] frames; every integer frame from the first key's to the
    /// last's must give a valid view (refused with the first that does not).
    ///
    /// Between keys `i` and `i + 1` (frames `t_i < t < t_{i+1}`, `h = t_{i+1} - t_i`,
    /// `s = (t - t_i) / h`) each of the twelve numbers (eye, target and up per component, then
    /// vfov_deg, the lens's aperture_radius and focus_distance) follows the cubic Hermite curve
    /// `p(t) = (2s³ - 3s² + 1) p_i + (s³ - 2s² + s) h m_i + (-2s³ + 3s²) p_{i+1} + (s³ - s²) h m_{i+1}`
    /// with the Catmull–Rom tangents of non-uniform spacing `m_i = (p_{i+1} - p_{i-1}) /
    /// (t_{i+1} - t_{i-1})`, one-sided `(p_1 - p_0) / (t_1 - t_0)` and `(p_n - p_{n-1}) / (t_n -
    /// t_{n-1})` at the ends. The curve passes through every key (at a key's frame the key itself
    /// is used, bit for bit), its derivative is continuous (C1), and keys on a straight line at
    /// constant speed are followed at constant speed whatever their spacing. The interpolated up
    /// is re-orthonormalised by [`Camera::look_at`], and the aperture's radius clamped at 0.
    /// Sums are taken in `f64`.
    pub fn keyed(
        name: impl Into<String>,
        width: u32,
        height: u32,
        keys: Vec<(u32, CameraKey)>,
    ) -> Result<SceneCamera, MotionError> {
        if keys.len() < 2 {
            return Err(MotionError::TooFewKeys(keys.len()));
        }
        for (index, pair) in keys.windows(2).enumerate() {
            if pair[1].0 <= pair[0].0 {
                return Err(MotionError::NotIncreasing {
                    index: index + 1,
                    frame: pair[1].0,
                    previous: pair[0].0,
                });
            }
        }
        let camera =
            SceneCamera { name: name.into(), width, height, motion: Motion::Keys(keys), offset: Vec3::ZERO };
        camera.check_every_frame(false)?;
        Ok(camera)
    }

    /// A turntable camera: `base` turned as [`Turntable`] says; `turntable.axis` need not be of
    /// unit length (it is normalised). `turntable.frames` must be in `1..=MAX_FRAMES` and every
    /// frame must give a valid view (refused with the first that does not).
    pub fn turntable(
        name: impl Into<String>,
        width: u32,
        height: u32,
        base: CameraKey,
        mut turntable: Turntable,
    ) -> Result<SceneCamera, MotionError> {
        if turntable.frames == 0 {
            return Err(MotionError::NoFrames);
        }
        turntable.axis =
            turntable.axis.try_normalize().ok_or(MotionError::Axis(turntable.axis.to_array()))?;
        let camera = SceneCamera {
            name: name.into(),
            width,
            height,
            motion: Motion::Turntable { base, turntable },
            offset: Vec3::ZERO,
        };
        camera.check_every_frame(true)?;
        Ok(camera)
    }

    /// Frames this camera's animation defines: keys' first..=last frame, turntable 0..=N-1;
    /// None for a still camera (valid at every frame).
    pub fn frames(&self) -> Option<RangeInclusive<u32>> {
        match &self.motion {
            Motion::Still(_) => None,
            Motion::Keys(keys) => Some(keys[0].0..=keys[keys.len() - 1].0),
            Motion::Turntable { turntable, .. } => Some(0..=turntable.frames - 1),
        }
    }

    /// The view at `frame` (clamped to the animation's range; a still camera ignores it), at
    /// this camera's resolution.
    pub fn view(&self, frame: u32) -> Camera {
        let mut view = match &self.motion {
            Motion::Still(view) => *view,
            Motion::Keys(_) | Motion::Turntable { .. } => self
                .key_view(frame)
                .expect("every frame of the animation was checked when the camera was built"),
        };
        view = view.with_resolution(self.width, self.height);
        view.eye -= self.offset;
        view
    }

    /// The same camera moved by `-offset` (for recentring). The views are still computed where
    /// the file put the camera and then moved, eye by `-offset` (the view's directions are
    /// untouched): a still camera moves exactly as `Camera::eye -= offset` does, and
    /// interpolation is not rounded differently by the move.
    pub fn translated(&self, offset: Vec3) -> SceneCamera {
        SceneCamera { offset: self.offset + offset, ..self.clone() }
    }

    /// The animated view at `frame` before any translation, at 1 x 1 (so that a resolution
    /// set later cannot make it fail); `None` if it is degenerate.
    fn key_view(&self, frame: u32) -> Option<Camera> {
        let key = match &self.motion {
            Motion::Still(view) => return Some(*view),
            Motion::Keys(keys) => keyed_at(keys, frame),
            Motion::Turntable { base, turntable } => turntable.turn(base, frame),
        };
        key.view(1, 1)
    }

    /// Checks the view at every frame of the animation's range, which must hold at most
    /// [`MAX_FRAMES`] frames.
    fn check_every_frame(&self, turntable: bool) -> Result<(), MotionError> {
        let range = self.frames().expect("an animated camera");
        let frames = u64::from(*range.end()) - u64::from(*range.start()) + 1;
        if frames > u64::from(MAX_FRAMES) {
            return Err(MotionError::TooManyFrames { turntable, frames });
        }
        match range.into_iter().find(|&f| self.key_view(f).is_none()) {
            Some(frame) => Err(MotionError::Degenerate { turntable, frame }),
            None => Ok(()),
        }
    }
}

/// The keyed view at `frame`, clamped to the keys' range; a key's own frame gives the key.
fn keyed_at(keys: &[(u32, CameraKey)], frame: u32) -> CameraKey {
    let frame = frame.clamp(keys[0].0, keys[keys.len() - 1].0);
    match keys.binary_search_by_key(&frame, |k| k.0) {
        Ok(i) => keys[i].1,
        Err(_) => CameraKey::from_components(interpolate(keys, f64::from(frame))),
    }
}

/// The Hermite curve of [`SceneCamera::keyed`] at time `t` (a frame number, not necessarily
/// whole) inside the keys' range.
fn interpolate(keys: &[(u32, CameraKey)], t: f64) -> [f64; COMPONENTS] {
    let time = |i: usize| f64::from(keys[i].0);
    let n = keys.len();
    // The segment [t_i, t_{i+1}] holding t.
    let i = keys.partition_point(|k| f64::from(k.0) <= t).clamp(1, n - 1) - 1;
    let tangent = |j: usize| {
        let (lo, hi) = (j.saturating_sub(1), (j + 1).min(n - 1));
        let (p, q) = (keys[lo].1.components(), keys[hi].1.components());
        let dt = time(hi) - time(lo);
        std::array::from_fn::<f64, COMPONENTS, _>(|c| (q[c] - p[c]) / dt)
    };
    let h = time(i + 1) - time(i);
    let s = (t - time(i)) / h;
    let (s2, s3) = (s * s, s * s * s);
    let (h00, h10, h01, h11) = (2.0 * s3 - 3.0 * s2 + 1.0, s3 - 2.0 * s2 + s, -2.0 * s3 + 3.0 * s2, s3 - s2);
    let (p0, p1) = (keys[i].1.components(), keys[i + 1].1.components());
    let (m0, m1) = (tangent(i), tangent(i + 1));
    std::array::from_fn(|c| h00 * p0[c] + h10 * h * m0[c] + h01 * p1[c] + h11 * h * m1[c])
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cornell() -> Camera {
        let vfov = 2.0 * (12.5f32 / 35.0).atan().to_degrees();
        Camera::look_at(Vec3::new(0.278, 0.273, -0.8), Vec3::new(0.278, 0.273, 0.0), Vec3::Y, vfov, 256, 256)
            .unwrap()
    }

    #[test]
    fn centre_and_corners_follow_the_convention() {
        let c = cornell();
        let centre = c.ray(128.0, 128.0);
        assert!((centre.dir - Vec3::Z).length() < 1e-6);
        // Looking along +Z with +Y up, the right vector is -X: the red wall (x ~ 0.556) is on
        // the left of the image.
        assert!((c.right - Vec3::new(-1.0, 0.0, 0.0)).length() < 1e-6);
        let top_left = c.ray(0.0, 0.0).dir;
        assert!(top_left.x > 0.0 && top_left.y > 0.0);
        // The vertical half angle is vfov / 2.
        let top = c.ray(128.0, 0.0).dir;
        assert!((top.y / top.z - 12.5 / 35.0).abs() < 1e-5);
    }

    /// Where `ray` crosses the plane `depth` in front of `c`'s eye along the view direction.
    fn on_plane(c: &Camera, ray: &Ray, depth: f32) -> Vec3 {
        let t = (depth - (ray.origin - c.eye).dot(c.forward)) / ray.dir.dot(c.forward);
        ray.at(t)
    }

    /// Lens samples spread over `[0, 1)²` (an 8 x 8 grid, corners included).
    fn lens_samples() -> impl Iterator<Item = [f32; 2]> {
        (0..64).map(|k| [(k % 8) as f32 / 7.0 * 0.999, (k / 8) as f32 / 7.0 * 0.999])
    }

    #[test]
    fn a_pinhole_lens_ray_is_the_pinhole_ray() {
        let c = cornell();
        for (x, y) in [(0.0, 0.0), (17.3, 200.9), (255.9, 128.0)] {
            for u in lens_samples() {
                assert_eq!(c.lens_ray(x, y, u), c.ray(x, y));
            }
        }
        assert_eq!(c.defocus_diameter(Vec3::new(0.3, 0.1, 0.9)), 0.0);
    }

    #[test]
    fn rays_of_a_pixel_meet_on_the_plane_in_focus() {
        let lens = Lens { aperture_radius: 0.05, focus_distance: 0.8 + 0.165 };
        let c = cornell().with_lens(lens).unwrap();
        for (x, y) in [(128.0, 128.0), (3.5, 250.25), (200.0, 40.0)] {
            let sharp = on_plane(&c, &c.ray(x, y), lens.focus_distance);
            let mut widest: f32 = 0.0;
            for u in lens_samples() {
                let ray = c.lens_ray(x, y, u);
                // It leaves the aperture's disc, in the lens plane...
                let off = ray.origin - c.eye;
                assert!(off.dot(c.forward).abs() < 1e-7 && off.length() <= lens.aperture_radius * 1.0001);
                widest = widest.max(off.length());
                // ...and passes through the pinhole ray's point on the plane in focus.
                let p = on_plane(&c, &ray, lens.focus_distance);
                assert!((p - sharp).length() < 1e-6, "({x}, {y}) {u:?}: {p} vs {sharp}");
                assert!((ray.dir.length() - 1.0).abs() < 1e-6);
            }
            assert!(widest > 0.99 * lens.aperture_radius, "the samples reach the rim: {widest}");
        }
    }

    #[test]
    fn out_of_focus_blur_grows_with_the_aperture_and_the_distance_from_focus() {
        // The radius of the spot the rays of one film position make on a plane `depth` ahead.
        let spot = |aperture_radius: f32, depth: f32| {
            let c = cornell().with_lens(Lens { aperture_radius, focus_distance: 1.0 }).unwrap();
            let centre = on_plane(&c, &c.ray(100.0, 60.0), depth);
            let widest = lens_samples()
                .map(|u| (on_plane(&c, &c.lens_ray(100.0, 60.0, u), depth) - centre).length())
                .fold(0.0, f32::max);
            (widest, c.defocus_diameter(c.eye + depth * c.forward))
        };
        for depth in [0.5, 1.5, 3.0] {
            let (small, coc) = spot(0.01, depth);
            let (large, large_coc) = spot(0.04, depth);
            // Four times the aperture, four times the blur; the spot fills the circle of
            // confusion 2 A |z - F| / F.
            assert!((large / small - 4.0).abs() < 1e-3, "depth {depth}: {small} {large}");
            assert!((coc - 2.0 * 0.01 * (depth - 1.0f32).abs()).abs() < 1e-6);
            assert!((large_coc / coc - 4.0).abs() < 1e-4);
            assert!(small <= 0.5 * coc * 1.001 && small > 0.45 * coc, "depth {depth}: {small} vs {coc}");
        }
        assert!(spot(0.02, 3.0).0 > spot(0.02, 1.5).0, "farther from focus, blurrier");
        assert!(spot(0.02, 1.0).0 < 1e-6, "sharp in focus");
    }

    #[test]
    fn bad_lenses_are_refused() {
        let c = cornell();
        for (aperture_radius, focus_distance) in
            [(-0.01, 1.0), (f32::NAN, 1.0), (0.1, 0.0), (0.1, -1.0), (0.0, f32::INFINITY)]
        {
            assert!(
                c.with_lens(Lens { aperture_radius, focus_distance }).is_none(),
                "{aperture_radius} {focus_distance}"
            );
        }
        assert!(c.with_lens(Lens { aperture_radius: 0.0, focus_distance: 0.5 }).is_some());
    }

    #[test]
    fn degenerate_frames_are_refused() {
        assert!(Camera::look_at(Vec3::ZERO, Vec3::ZERO, Vec3::Y, 40.0, 8, 8).is_none());
        assert!(Camera::look_at(Vec3::ZERO, Vec3::Y, Vec3::Y, 40.0, 8, 8).is_none());
        assert!(Camera::look_at(Vec3::ZERO, Vec3::Z, Vec3::Y, 180.0, 8, 8).is_none());
        assert!(Camera::look_at(Vec3::ZERO, Vec3::Z, Vec3::Y, 40.0, 0, 8).is_none());
    }
    fn key(eye: [f32; 3], target: [f32; 3], vfov_deg: f32) -> CameraKey {
        CameraKey {
            eye: Vec3::from(eye),
            target: Vec3::from(target),
            up: Vec3::Y,
            vfov_deg,
            lens: Lens::PINHOLE,
        }
    }

    /// Four keys at non-uniform frames, the eye swinging around and the field of view changing.
    fn swing() -> Vec<(u32, CameraKey)> {
        vec![
            (0, key([0.0, 0.0, -2.0], [0.0, 0.0, 0.0], 40.0)),
            (10, key([1.5, 0.3, -1.5], [0.1, 0.0, 0.0], 45.0)),
            (13, key([2.0, 0.5, 0.0], [0.0, 0.2, 0.0], 30.0)),
            (40, key([0.5, 1.0, 2.0], [0.0, 0.0, 0.1], 50.0)),
        ]
    }

    #[test]
    fn keyed_views_pass_through_every_key_exactly() {
        let keys = swing();
        let cam = SceneCamera::keyed("swing", 64, 32, keys.clone()).unwrap();
        assert_eq!(cam.frames(), Some(0..=40));
        for (frame, k) in &keys {
            assert_eq!(cam.view(*frame), k.view(64, 32).unwrap(), "frame {frame}");
        }
        // Outside the range the ends hold.
        assert_eq!(cam.view(1000), keys[3].1.view(64, 32).unwrap());
        // An inner frame lies nearer its key than the next key is.
        let near = cam.view(11);
        let (d, span) = ((near.eye - keys[1].1.eye).length(), (keys[2].1.eye - keys[1].1.eye).length());
        assert!(d > 0.0 && d < span, "{near:?}");
        assert_eq!((near.width, near.height), (64, 32));
    }

    #[test]
    fn keyed_views_are_smooth_at_an_interior_key() {
        let keys = swing();
        // Derivative at each interior key from the left and from the right, by finite
        // differences of the curve (the C1 property); and the tangent is Catmull-Rom's.
        for i in 1..keys.len() - 1 {
            let t = f64::from(keys[i].0);
            let eps = 1e-4;
            let (before, at, after) =
                (interpolate(&keys, t - eps), interpolate(&keys, t), interpolate(&keys, t + eps));
            let (p, q) = (keys[i - 1].1.components(), keys[i + 1].1.components());
            let dt = f64::from(keys[i + 1].0 - keys[i - 1].0);
            for c in 0..COMPONENTS {
                let left = (at[c] - before[c]) / eps;
                let right = (after[c] - at[c]) / eps;
                let catmull_rom = (q[c] - p[c]) / dt;
                assert!((left - right).abs() < 1e-3, "key {i}, component {c}: {left} vs {right}");
                assert!((left - catmull_rom).abs() < 1e-3, "key {i}, component {c}: {left} vs {catmull_rom}");
            }
        }
        // A kink the curve must not have: the same check on linear interpolation would fail
        // here (the slopes on either side of key 1 differ by this much).
        let slope = |a: usize, b: usize| (keys[b].1.eye.x - keys[a].1.eye.x) / (keys[b].0 - keys[a].0) as f32;
        assert!((slope(0, 1) - slope(1, 2)).abs() > 0.01);
    }

    #[test]
    fn non_uniformly_spaced_keys_on_a_line_are_followed_at_constant_speed() {
        // Keys at frames 0, 1, 10 and 30 on a straight line at one unit per frame: the
        // non-uniform tangents reproduce the line (the uniform formula would not).
        let at = |f: u32| key([f as f32, 0.0, -5.0], [f as f32, 0.0, 0.0], 40.0);
        let keys: Vec<_> = [0, 1, 10, 30].into_iter().map(|f| (f, at(f))).collect();
        let cam = SceneCamera::keyed("line", 8, 8, keys.clone()).unwrap();
        for f in 0..=30 {
            let eye = cam.view(f).eye;
            assert!((eye - at(f).eye).length() < 1e-5, "frame {f}: {eye:?}");
        }
        // The uniform Catmull-Rom tangent (p_{i+1} - p_{i-1}) / 2 in key index would be 5 per
        // frame at frame 1 and overshoot: the curve would leave the line between 1 and 10.
        let mid = interpolate(&keys, 5.5);
        assert!((mid[0] - 5.5).abs() < 1e-9, "{mid:?}");
    }

    #[test]
    fn the_lens_is_keyed_like_the_rest_and_the_radius_never_negative() {
        // A pinhole that opens and closes again, focus pulled from 1 m to 3 m.
        let lens = |aperture_radius: f32, focus_distance: f32| Lens { aperture_radius, focus_distance };
        let at = |a: f32, f: f32| CameraKey { lens: lens(a, f), ..key([0.0, 0.0, -2.0], [0.0; 3], 40.0) };
        let keys = vec![(0, at(0.0, 1.0)), (10, at(0.0, 1.0)), (20, at(0.05, 3.0)), (30, at(0.0, 3.0))];
        let cam = SceneCamera::keyed("pull", 8, 8, keys.clone()).unwrap();
        for (frame, k) in &keys {
            let expected = if k.lens.is_pinhole() { Lens::PINHOLE } else { k.lens };
            assert_eq!(cam.view(*frame).lens, expected);
        }
        // The Hermite curve undershoots 0 just before frame 10 and after 20; the radius is
        // clamped there.
        assert!(interpolate(&keys, 8.0)[10] < 0.0);
        assert_eq!(cam.view(8).lens.aperture_radius, 0.0);
        let mid = cam.view(15).lens;
        assert!(mid.aperture_radius > 0.0 && mid.aperture_radius < 0.05, "{mid:?}");
        assert!(mid.focus_distance > 1.0 && mid.focus_distance < 3.0, "{mid:?}");
        // A turntable keeps the lens.
        let turntable = Turntable { frames: 4, center: Vec3::ZERO, axis: Vec3::Y, degrees: 360.0 };
        let cam = SceneCamera::turntable("t", 8, 8, at(0.02, 2.0), turntable).unwrap();
        assert_eq!(cam.view(3).lens, lens(0.02, 2.0));
        // Focus pulled fast to 5 cm and held: the curve overshoots through 0 after the pull, a
        // degenerate frame, refused as any other.
        let keys = vec![(0, at(0.01, 2.0)), (10, at(0.01, 0.05)), (20, at(0.01, 0.05))];
        assert!(interpolate(&keys, 13.0)[11] < 0.0);
        let cam = SceneCamera::keyed("fast", 8, 8, keys);
        assert!(matches!(cam, Err(MotionError::Degenerate { turntable: false, frame: 11..=19 })), "{cam:?}");
    }

    #[test]
    fn turntable_frame_0_is_the_base_and_a_quarter_of_the_frames_a_quarter_turn() {
        let base = CameraKey {
            eye: Vec3::new(0.3, 0.7, 2.0),
            target: Vec3::ZERO,
            up: Vec3::Y,
            vfov_deg: 35.0,
            lens: Lens::PINHOLE,
        };
        let turntable = Turntable { frames: 8, center: Vec3::ZERO, axis: Vec3::Y * 3.0, degrees: 360.0 };
        let cam = SceneCamera::turntable("turn", 16, 16, base, turntable).unwrap();
        assert_eq!(cam.frames(), Some(0..=7));
        assert_eq!(cam.view(0), base.view(16, 16).unwrap());
        // Frame 2 of 8 is 90 degrees counter-clockwise about +Y: +Z goes to +X.
        let quarter = cam.view(2);
        assert!((quarter.eye - Vec3::new(2.0, 0.7, -0.3)).length() < 1e-6, "{quarter:?}");
        let up = base.view(16, 16).unwrap().up;
        assert!((quarter.up - Vec3::new(up.z, up.y, -up.x)).length() < 1e-6, "{quarter:?}");
        // The loop closes: frame 8 would be frame 0 again, so frame 7 is one step short of it
        // and later frames are clamped to 7.
        assert_eq!(cam.view(100), cam.view(7));
        // About a line off the origin, the target turns too.
        let off = Turntable { center: Vec3::new(1.0, 0.0, 0.0), ..turntable };
        let cam = SceneCamera::turntable("turn", 16, 16, base, off).unwrap();
        let half = cam.view(4);
        assert!((half.eye - Vec3::new(1.7, 0.7, -2.0)).length() < 1e-6, "{half:?}");
        assert!((half.forward - Vec3::new(0.3, -0.7, 2.0).normalize()).length() < 1e-6);
    }

    #[test]
    fn animations_that_cannot_be_rendered_are_refused() {
        let k = key([0.0, 0.0, -2.0], [0.0, 0.0, 0.0], 40.0);
        assert_eq!(SceneCamera::keyed("a", 8, 8, vec![(3, k)]), Err(MotionError::TooFewKeys(1)));
        assert_eq!(
            SceneCamera::keyed("a", 8, 8, vec![(3, k), (5, k), (5, k)]),
            Err(MotionError::NotIncreasing { index: 2, frame: 5, previous: 5 })
        );
        let long = SceneCamera::keyed("a", 8, 8, vec![(0, k), (MAX_FRAMES, k)]);
        assert_eq!(long, Err(MotionError::TooManyFrames { turntable: false, frames: 1_000_001 }));
        assert!(SceneCamera::keyed("a", 8, 8, vec![(0, k), (MAX_FRAMES - 1, k)]).is_ok());
        // Eye and target swap places: at frame 1 they meet.
        let swap = vec![
            (0, key([-1.0, 0.0, 0.0], [1.0, 0.0, 0.0], 40.0)),
            (2, key([1.0, 0.0, 0.0], [-1.0, 0.0, 0.0], 40.0)),
        ];
        let e = SceneCamera::keyed("a", 8, 8, swap).unwrap_err();
        assert_eq!(e, MotionError::Degenerate { turntable: false, frame: 1 });
        assert_eq!(e.field(), "key");
        // The field of view overshoots 180 between keys (a fast rise into a slow one).
        let fov = |f: u32, vfov: f32| (f, key([0.0; 3], [0.0, 0.0, 1.0], vfov));
        let wide = vec![fov(0, 100.0), fov(1, 170.0), fov(20, 178.0)];
        assert!(interpolate(&wide, 6.0)[9] > 180.0);
        assert!(matches!(
            SceneCamera::keyed("a", 8, 8, wide),
            Err(MotionError::Degenerate { frame: 2..=6, .. })
        ));
        let t = Turntable { frames: 4, center: Vec3::ZERO, axis: Vec3::Y, degrees: 360.0 };
        assert_eq!(
            SceneCamera::turntable("t", 8, 8, k, Turntable { frames: 0, ..t }).unwrap_err().field(),
            "turntable.frames"
        );
        let e = SceneCamera::turntable("t", 8, 8, k, Turntable { axis: Vec3::ZERO, ..t }).unwrap_err();
        assert_eq!((e.field().as_str(), e), ("turntable.axis", MotionError::Axis([0.0; 3])));
        // A turn is rigid, so only rounding can break a view: about a centre far away, the eye
        // 2 m from the target is rounded onto it once the turn puts both far from the origin.
        let far = Turntable { center: Vec3::new(3e38, 0.0, 0.0), ..t };
        let e = SceneCamera::turntable("t", 8, 8, k, far).unwrap_err();
        assert_eq!(e, MotionError::Degenerate { turntable: true, frame: 1 });
        assert_eq!(e.field(), "turntable");
    }

    #[test]
    fn a_translated_camera_moves_its_eye_only() {
        let c = cornell();
        let offset = Vec3::new(1e5, -3.0, 0.25);
        let still = SceneCamera::still("c", c).translated(offset);
        let mut moved = c;
        moved.eye -= offset;
        assert_eq!(still.view(7), moved);
        assert_eq!(still.frames(), None);
        let keyed = SceneCamera::keyed("k", 8, 8, swing()).unwrap();
        let moved = keyed.translated(offset);
        for f in [0, 5, 11, 40] {
            let (mut a, b) = (keyed.view(f), moved.view(f));
            a.eye -= offset;
            assert_eq!(a, b, "frame {f}");
        }
    }
}
