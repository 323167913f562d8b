//! Axis-aligned bounding boxes.

use glam::Vec3;

/// An axis-aligned box; the empty box has `min = +inf`, `max = -inf`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Aabb {
    pub min: Vec3,
    pub max: Vec3,
}

impl Default for Aabb {
    fn default() -> Self {
        Aabb::EMPTY
    }
}

impl Aabb {
    pub const EMPTY: Aabb = Aabb { min: Vec3::splat(f32::INFINITY), max: Vec3::splat(f32::NEG_INFINITY) };

    pub fn from_points(points: impl IntoIterator<Item = Vec3>) -> Self {
        points.into_iter().fold(Aabb::EMPTY, |b, p| b.grow(p))
    }

    #[inline]
    pub fn grow(self, p: Vec3) -> Self {
        Aabb { min: self.min.min(p), max: self.max.max(p) }
    }

    #[inline]
    pub fn union(self, o: Aabb) -> Self {
        Aabb { min: self.min.min(o.min), max: self.max.max(o.max) }
    }

    #[inline]
    pub fn is_empty(&self) -> bool {
        self.min.x > self.max.x || self.min.y > self.max.y || self.min.z > self.max.z
    }

    #[inline]
    pub fn extent(&self) -> Vec3 {
        if self.is_empty() {
            Vec3::ZERO
        } else {
            self.max - self.min
        }
    }

    #[inline]
    pub fn center(&self) -> Vec3 {
        0.5 * (self.min + self.max)
    }

    /// Surface area (0 for an empty box).
    #[inline]
    pub fn area(&self) -> f32 {
        let e = self.extent();
        2.0 * (e.x * e.y + e.y * e.z + e.z * e.x)
    }

    /// Index of the longest axis ([`longest_axis`] of the extent).
    pub fn longest_axis(&self) -> usize {
        longest_axis(self.extent())
    }

    /// Centre and radius of a sphere that encloses the box.
    pub fn bounding_sphere(&self) -> (Vec3, f32) {
        (self.center(), 0.5 * self.extent().length())
    }

    pub fn contains(&self, p: Vec3) -> bool {
        p.cmpge(self.min).all() && p.cmple(self.max).all()
    }
}

/// Index of the largest component of a box's `extent`: x when it ties with y or z, y when it
/// ties with z. The BVH builder and the photon kd-tree pick their split axes with it.
#[inline]
pub fn longest_axis(extent: Vec3) -> usize {
    let e = extent;
    if e.x >= e.y && e.x >= e.z {
        0
    } else if e.y >= e.z {
        1
    } else {
        2
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn grow_union_area() {
        let b = Aabb::from_points([Vec3::ZERO, Vec3::new(1.0, 2.0, 3.0)]);
        assert_eq!(b.area(), 2.0 * (2.0 + 6.0 + 3.0));
        assert_eq!(b.longest_axis(), 2);
        assert!(Aabb::EMPTY.is_empty());
        assert_eq!(Aabb::EMPTY.area(), 0.0);
        assert_eq!(Aabb::EMPTY.union(b), b);
        assert!(b.contains(Vec3::new(0.5, 1.0, 1.0)));
    }

    #[test]
    fn longest_axis_breaks_ties_towards_x_then_y() {
        for (e, axis) in [
            ([3.0, 2.0, 1.0], 0),
            ([1.0, 3.0, 2.0], 1),
            ([1.0, 2.0, 3.0], 2),
            ([2.0, 2.0, 2.0], 0),
            ([2.0, 2.0, 1.0], 0),
            ([2.0, 1.0, 2.0], 0),
            ([1.0, 2.0, 2.0], 1),
            ([0.0, 0.0, 0.0], 0),
        ] {
            assert_eq!(longest_axis(Vec3::from_array(e)), axis, "{e:?}");
        }
        assert_eq!(Aabb::EMPTY.longest_axis(), 0);
    }
}
