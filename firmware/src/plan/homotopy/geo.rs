//! Planar geometry in `f64` for the homotopy planner: points, orientation, segment tests, polygons, ear clipping.
//!
//! `f64` throughout: orientation tests on metre-scale coordinates with millimetre features, and the logarithms of
//! the L-values (see [`super::lvalue`]), need more than `f32`'s 24 bits. On the Cortex-M7 `f64` is IEEE-exact
//! (hardware double on the M7 FPU variant, soft-float otherwise), so results are bit-identical to the host.

use core::ops::{Add, Mul, Sub};

/// Tolerance for geometric predicates, in metres (squared where noted). Default 1e-9.
pub const EPS: f64 = 1e-9;

/// A point (or vector) on a tether-demand plane: `x` across the slope, `y` up the slope, metres.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Pt {
    /// Across-slope coordinate (m).
    pub x: f64,
    /// Up-slope coordinate (m); `+y` is the upslope direction of the plane.
    pub y: f64,
}

/// Shorthand constructor.
pub const fn pt(x: f64, y: f64) -> Pt {
    Pt { x, y }
}

impl Add for Pt {
    type Output = Pt;
    fn add(self, o: Pt) -> Pt {
        pt(self.x + o.x, self.y + o.y)
    }
}
impl Sub for Pt {
    type Output = Pt;
    fn sub(self, o: Pt) -> Pt {
        pt(self.x - o.x, self.y - o.y)
    }
}
impl Mul<f64> for Pt {
    type Output = Pt;
    fn mul(self, s: f64) -> Pt {
        pt(self.x * s, self.y * s)
    }
}

impl Pt {
    /// 2D cross product (z of the 3D cross).
    pub fn cross(self, o: Pt) -> f64 {
        self.x * o.y - self.y * o.x
    }
    /// Dot product.
    pub fn dot(self, o: Pt) -> f64 {
        self.x * o.x + self.y * o.y
    }
    /// Euclidean norm.
    pub fn norm(self) -> f64 {
        libm::sqrt(self.dot(self))
    }
    /// Distance to `o`.
    pub fn dist(self, o: Pt) -> f64 {
        (self - o).norm()
    }
    /// True when both coordinates are finite.
    pub fn is_finite(self) -> bool {
        self.x.is_finite() && self.y.is_finite()
    }
}

/// Twice the signed area of triangle `a b c` (positive when counter-clockwise).
pub fn orient(a: Pt, b: Pt, c: Pt) -> f64 {
    (b - a).cross(c - a)
}

/// Orientation sign with a scale-aware tolerance: 1 (left), -1 (right), 0 (collinear).
pub fn orient_sign(a: Pt, b: Pt, c: Pt) -> i8 {
    let o = orient(a, b, c);
    let scale = (b - a).norm() * (c - a).norm() + 1.0;
    if o > EPS * scale {
        1
    } else if o < -EPS * scale {
        -1
    } else {
        0
    }
}

/// True when the open segments `p q` and `a b` cross at a single interior point of both.
pub fn segments_cross_properly(p: Pt, q: Pt, a: Pt, b: Pt) -> bool {
    let d1 = orient_sign(p, q, a);
    let d2 = orient_sign(p, q, b);
    let d3 = orient_sign(a, b, p);
    let d4 = orient_sign(a, b, q);
    d1 * d2 < 0 && d3 * d4 < 0
}

/// True when `c` lies strictly inside segment `a b` (collinear, between, not at an end).
pub fn point_strictly_on_segment(c: Pt, a: Pt, b: Pt) -> bool {
    if orient_sign(a, b, c) != 0 {
        return false;
    }
    let ab = b - a;
    let t = (c - a).dot(ab);
    let l2 = ab.dot(ab);
    t > EPS * (1.0 + l2) && t < l2 - EPS * (1.0 + l2)
}

/// True when segments `p q` and `a b` share any point (touching counts).
pub fn segments_intersect(p: Pt, q: Pt, a: Pt, b: Pt) -> bool {
    let d1 = orient_sign(p, q, a);
    let d2 = orient_sign(p, q, b);
    let d3 = orient_sign(a, b, p);
    let d4 = orient_sign(a, b, q);
    if d1 * d2 < 0 && d3 * d4 < 0 {
        return true;
    }
    let on = |c: Pt, s0: Pt, s1: Pt| {
        orient_sign(s0, s1, c) == 0
            && c.x >= s0.x.min(s1.x) - EPS
            && c.x <= s0.x.max(s1.x) + EPS
            && c.y >= s0.y.min(s1.y) - EPS
            && c.y <= s0.y.max(s1.y) + EPS
    };
    on(a, p, q) || on(b, p, q) || on(p, a, b) || on(q, a, b)
}

/// Iterator over the closed edges `(v[i], v[i+1 mod n])` of a polygon.
pub fn polygon_edges(v: &[Pt]) -> impl Iterator<Item = (Pt, Pt)> + '_ {
    v.iter().zip(v.iter().cycle().skip(1)).map(|(a, b)| (*a, *b))
}

/// Signed area of a polygon (positive when counter-clockwise).
pub fn polygon_area(v: &[Pt]) -> f64 {
    0.5 * polygon_edges(v).map(|(a, b)| a.cross(b)).sum::<f64>()
}

/// Point-in-polygon by crossing number; points on the boundary count as outside when `strict`, inside otherwise.
pub fn point_in_polygon(p: Pt, v: &[Pt], strict: bool) -> bool {
    for (a, b) in polygon_edges(v) {
        if point_strictly_on_segment(p, a, b) || p.dist(a) < EPS {
            return !strict;
        }
    }
    let mut inside = false;
    for (a, b) in polygon_edges(v) {
        if (a.y > p.y) != (b.y > p.y) {
            let x = a.x + (p.y - a.y) * (b.x - a.x) / (b.y - a.y);
            if x > p.x {
                inside = !inside;
            }
        }
    }
    inside
}

/// True when `v` is a simple polygon (no two non-adjacent edges intersect, no zero-length edge).
pub fn polygon_is_simple(v: &[Pt]) -> bool {
    let n = v.len();
    if n < 3 {
        return false;
    }
    for (i, (a, b)) in polygon_edges(v).enumerate() {
        if a.dist(b) < EPS {
            return false;
        }
        for (j, (c, d)) in polygon_edges(v).enumerate() {
            if j <= i {
                continue;
            }
            let adjacent = j == i + 1 || (i == 0 && j == n - 1);
            if adjacent {
                // Adjacent edges may only share their common corner: reject folds back onto each other.
                let shared = if j == i + 1 { b } else { a };
                let (o1, o2) = if j == i + 1 { (a, d) } else { (b, c) };
                if orient_sign(o1, shared, o2) == 0 && (o1 - shared).dot(o2 - shared) > 0.0 {
                    return false;
                }
            } else if segments_intersect(a, b, c, d) {
                return false;
            }
        }
    }
    true
}

/// True when two simple polygons share any point (edges touching or one inside the other).
pub fn polygons_overlap(a: &[Pt], b: &[Pt]) -> bool {
    for (p, q) in polygon_edges(a) {
        for (r, s) in polygon_edges(b) {
            if segments_intersect(p, q, r, s) {
                return true;
            }
        }
    }
    a.first().is_some_and(|p| point_in_polygon(*p, b, false)) || b.first().is_some_and(|p| point_in_polygon(*p, a, false))
}

/// Ear clipping of a simple counter-clockwise polygon into triangles (corner indices), for decomposing a
/// non-convex obstacle into convex pieces. Returns the number of triangles written (`n - 2` on success, fewer if
/// `out` is too small or the polygon is degenerate). O(n^3), bounded by `n^2` clip attempts.
pub fn ear_clip(v: &[Pt], out: &mut [[u8; 3]]) -> usize {
    let n = v.len().min(crate::config::homotopy::MAX_OBSTACLE_VERTICES);
    let mut idx: heapless::Vec<u8, { crate::config::homotopy::MAX_OBSTACLE_VERTICES }> = heapless::Vec::new();
    for i in 0..n {
        let _ = idx.push(i as u8);
    }
    let at = |i: u8| v.get(usize::from(i)).copied().unwrap_or_default();
    let mut written = 0;
    let mut attempts = 0;
    while idx.len() > 3 && attempts < n * n {
        attempts += 1;
        let m = idx.len();
        let mut clipped = false;
        for k in 0..m {
            let (Some(&ia), Some(&ib), Some(&ic)) = (idx.get((k + m - 1) % m), idx.get(k), idx.get((k + 1) % m)) else {
                continue;
            };
            let (a, b, c) = (at(ia), at(ib), at(ic));
            if orient(a, b, c) <= EPS {
                continue;
            }
            let blocked = idx
                .iter()
                .filter(|&&j| j != ia && j != ib && j != ic)
                .any(|&j| point_in_polygon(at(j), &[a, b, c], false));
            if blocked {
                continue;
            }
            if let Some(slot) = out.get_mut(written) {
                *slot = [ia, ib, ic];
                written += 1;
            } else {
                return written;
            }
            let _ = remove_at(&mut idx, k);
            clipped = true;
            break;
        }
        if !clipped {
            return written;
        }
    }
    if let (Some(&a), Some(&b), Some(&c), Some(slot)) = (idx.first(), idx.get(1), idx.get(2), out.get_mut(written)) {
        *slot = [a, b, c];
        written += 1;
    }
    written
}

/// The 4-neighbours of cell `i` of a row-major `cols` x `rows` grid (left, right, down, up), `None` off the grid.
pub fn grid_neighbours(i: usize, cols: usize, rows: usize) -> [Option<usize>; 4] {
    let (c, r) = (i % cols.max(1), i / cols.max(1));
    [
        (c > 0).then(|| i - 1),
        (c + 1 < cols).then(|| i + 1),
        (r > 0).then(|| i - cols),
        (r + 1 < rows).then(|| i + cols),
    ]
}

/// Sorts `v` by `less` (a strict weak order) with no panic path: heapsort (O(n log n), every loop bounded, every
/// index through `get`). The flight build links with `panic-never`, and core's sorts keep a panic for an order
/// that violates totality. Used with total orders (ties broken by ids), so the result is the one order there is.
pub fn sort_by<T: Copy>(v: &mut [T], mut less: impl FnMut(&T, &T) -> bool) {
    let n = v.len();
    let mut i = n / 2;
    while i > 0 {
        i -= 1;
        sift_down(v, i, n, &mut less);
    }
    let mut end = n;
    while end > 1 {
        end -= 1;
        swap_at(v, 0, end);
        sift_down(v, 0, end, &mut less);
    }
}

fn swap_at<T: Copy>(v: &mut [T], i: usize, j: usize) {
    if let (Some(&a), Some(&b)) = (v.get(i), v.get(j)) {
        if let Some(x) = v.get_mut(i) {
            *x = b;
        }
        if let Some(y) = v.get_mut(j) {
            *y = a;
        }
    }
}

fn sift_down<T: Copy>(v: &mut [T], mut root: usize, end: usize, less: &mut impl FnMut(&T, &T) -> bool) {
    // the root at least doubles each pass: at most usize::BITS passes
    for _ in 0..usize::BITS {
        let child = root.saturating_mul(2).saturating_add(1);
        if child >= end {
            return;
        }
        let mut c = child;
        if child + 1 < end {
            if let (Some(a), Some(b)) = (v.get(child), v.get(child + 1)) {
                if less(a, b) {
                    c = child + 1;
                }
            }
        }
        match (v.get(root), v.get(c)) {
            (Some(r), Some(x)) if less(r, x) => {
                swap_at(v, root, c);
                root = c;
            }
            _ => return,
        }
    }
}

/// Removes element `i` of `v`, shifting the rest down (heapless's `remove` keeps a panic for an index out of range;
/// this does nothing then).
pub fn remove_at<T: Copy, const N: usize>(v: &mut heapless::Vec<T, N>, i: usize) -> Option<T> {
    let out = v.get(i).copied()?;
    let n = v.len();
    for k in i..n.saturating_sub(1) {
        if let Some(&next) = v.get(k + 1) {
            if let Some(slot) = v.get_mut(k) {
                *slot = next;
            }
        }
    }
    v.truncate(n.saturating_sub(1));
    Some(out)
}
