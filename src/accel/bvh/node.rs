//! The flattened node of the BVH: 32 bytes, two siblings per 64-byte cache line.
//!
//! The two children of an interior node are stored side by side as a [`NodePair`] aligned to a
//! cache line, so the traversal tests both with a single memory fetch; pairs are laid out in
//! depth-first order. An interior node stores the index of its children's pair, a leaf the
//! range of its triangles in the leaf-ordered triangle array.

use crate::geometry::Aabb;
use glam::{Vec3, Vec3A};

/// Number of bits of `meta` holding the split axis; the rest holds the leaf's triangle count.
const AXIS_BITS: u32 = 2;

/// One BVH node: bounds (`min`, `max`), then either the children's pair index (interior) or the
/// first triangle (leaf), and `count << 2 | axis` (`count == 0` for an interior node).
/// An interior node's `offset` is the index of its children's [`NodePair`].
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[repr(C, align(32))]
pub struct Node {
    pub min: [f32; 3],
    /// Interior: index of the children's [`NodePair`]. Leaf: index of the first triangle.
    pub offset: u32,
    pub max: [f32; 3],
    /// `count << 2 | axis`; `count` is 0 for interior nodes.
    pub meta: u32,
}

const _: () = assert!(std::mem::size_of::<Node>() == 32);

/// The two children of an interior node, in one 64-byte cache line.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[repr(C, align(64))]
pub struct NodePair(pub [Node; 2]);

const _: () = assert!(std::mem::size_of::<NodePair>() == 64);

impl Node {
    /// A leaf over triangles `first .. first + count` (`count >= 1`).
    pub fn leaf(bounds: Aabb, first: u32, count: u32) -> Self {
        debug_assert!(count >= 1);
        Node {
            min: bounds.min.to_array(),
            offset: first,
            max: bounds.max.to_array(),
            meta: count << AXIS_BITS,
        }
    }

    /// An interior node whose children are the pair at index `pair`.
    pub fn interior(bounds: Aabb, pair: u32, axis: u32) -> Self {
        debug_assert!(axis < 3);
        Node { min: bounds.min.to_array(), offset: pair, max: bounds.max.to_array(), meta: axis }
    }

    #[inline(always)]
    pub fn is_leaf(&self) -> bool {
        self.meta >> AXIS_BITS != 0
    }

    /// Triangle count of a leaf (0 for an interior node).
    #[inline(always)]
    pub fn count(&self) -> u32 {
        self.meta >> AXIS_BITS
    }

    /// Split axis of an interior node.
    #[inline(always)]
    pub fn axis(&self) -> usize {
        (self.meta & ((1 << AXIS_BITS) - 1)) as usize
    }

    #[inline(always)]
    pub fn min_a(&self) -> Vec3A {
        Vec3A::from_array(self.min)
    }

    #[inline(always)]
    pub fn max_a(&self) -> Vec3A {
        Vec3A::from_array(self.max)
    }

    pub fn bounds(&self) -> Aabb {
        Aabb { min: Vec3::from_array(self.min), max: Vec3::from_array(self.max) }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn packs_leaf_and_interior() {
        let b = Aabb::from_points([Vec3::ZERO, Vec3::ONE]);
        let l = Node::leaf(b, 7, 5);
        assert!(l.is_leaf());
        assert_eq!((l.offset, l.count()), (7, 5));
        let i = Node::interior(b, 9, 2);
        assert!(!i.is_leaf());
        assert_eq!((i.offset, i.axis(), i.count()), (9, 2, 0));
        assert_eq!(i.bounds(), b);
    }
}
