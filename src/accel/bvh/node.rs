//! The flattened node of the BVH: four children's boxes in structure-of-arrays layout, 128
//! bytes (two cache lines).
//!
//! `bounds[axis][0]` holds the four children's minima along `axis`, one per lane, and
//! `bounds[axis][1]` their maxima, so one ray is tested against all four boxes with a handful
//! of 4-wide SIMD operations. Unused slots have empty bounds (`+inf` minima, `-inf` maxima),
//! which every ray misses, and the child [`EMPTY`].

use crate::geometry::Aabb;
use glam::{Vec3, Vec4};

/// Set in a child reference to a leaf: `LEAF | first_packet << PACKET_BITS | (packets - 1)`.
pub const LEAF: u32 = 1 << 31;
/// Low bits of a leaf reference holding its number of [`Tri4`](crate::accel::triangle::Tri4)
/// packets minus one.
pub const PACKET_BITS: u32 = 3;
/// Most packets a leaf may have.
pub const MAX_PACKETS: u32 = 1 << PACKET_BITS;
/// Packets are numbered below this.
pub const MAX_FIRST_PACKET: u32 = 1 << (31 - PACKET_BITS);
/// An unused child slot.
pub const EMPTY: u32 = u32::MAX;

/// One 4-wide node: the four children's boxes and references. A child reference is the index of an interior
/// node, a leaf reference (bit 31 set) or `u32::MAX` for an unused slot.
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C, align(64))]
pub struct Node4 {
    pub bounds: [[Vec4; 2]; 3],
    pub child: [u32; 4],
}

const _: () = assert!(std::mem::size_of::<Node4>() == 128);

impl Default for Node4 {
    fn default() -> Self {
        let empty = [Vec4::INFINITY, Vec4::NEG_INFINITY];
        Node4 { bounds: [empty; 3], child: [EMPTY; 4] }
    }
}

impl Node4 {
    /// Sets child slot `i` to `child` with bounds `b`.
    pub fn set(&mut self, i: usize, b: Aabb, child: u32) {
        for (axis, [lo, hi]) in self.bounds.iter_mut().enumerate() {
            lo[i] = b.min[axis];
            hi[i] = b.max[axis];
        }
        self.child[i] = child;
    }

    /// The bounds of child slot `i`.
    pub fn child_bounds(&self, i: usize) -> Aabb {
        let [x, y, z] = self.bounds;
        Aabb { min: Vec3::new(x[0][i], y[0][i], z[0][i]), max: Vec3::new(x[1][i], y[1][i], z[1][i]) }
    }
}

/// A leaf reference over `packets` packets starting at `first`.
pub fn leaf_ref(first: u32, packets: u32) -> u32 {
    assert!(first < MAX_FIRST_PACKET, "too many triangles for the BVH's leaf references");
    assert!((1..=MAX_PACKETS).contains(&packets));
    LEAF | first << PACKET_BITS | (packets - 1)
}

/// `(first packet, packet count)` of a leaf reference.
#[inline(always)]
pub fn leaf_range(r: u32) -> (usize, usize) {
    (((r & !LEAF) >> PACKET_BITS) as usize, ((r & (MAX_PACKETS - 1)) + 1) as usize)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn packs_leaves_and_bounds() {
        let r = leaf_ref(12345, 2);
        assert!(r & LEAF != 0 && r != EMPTY);
        assert_eq!(leaf_range(r), (12345, 2));
        let mut n = Node4::default();
        let b = Aabb::from_points([Vec3::ZERO, Vec3::ONE]);
        n.set(2, b, 9);
        assert_eq!(n.child_bounds(2), b);
        assert_eq!(n.child, [EMPTY, EMPTY, 9, EMPTY]);
        assert!(n.child_bounds(0).is_empty());
    }
}
