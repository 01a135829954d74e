//! A 2-D bounding volume hierarchy over triangles projected into light space.
//!
//! All rays of a directional-light shadow map are parallel (along +w in light space), so a ray
//! is a point (u, v) and a node is hit iff its (u, v) box contains the point. The binned SAH
//! cost therefore uses the projected box *area* (the probability that a uniformly placed
//! parallel ray hits the box), not the surface area. Traversal returns *all* hits.

/// A triangle in light space with everything needed to intersect it with a ray (u, v).
#[derive(Clone, Copy, Debug)]
pub struct LTri {
    /// Projected vertices (u, v).
    pub p: [[f64; 2]; 3],
    /// Depth coordinate w at vertex 0.
    pub w0: f64,
    /// Plane slopes ∂w/∂u = −n_u/n_w and ∂w/∂v = −n_v/n_w from the geometric normal.
    pub su: f64,
    /// ∂w/∂v (see `su`).
    pub sv: f64,
}

impl LTri {
    /// Builds a light-space triangle from vertices (u, v, w); `None` if it is parallel to the
    /// rays (zero projected area), where it can only be grazed along an edge.
    pub fn new(a: [f64; 3], b: [f64; 3], c: [f64; 3]) -> Option<LTri> {
        let e1 = [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
        let e2 = [c[0] - a[0], c[1] - a[1], c[2] - a[2]];
        let n = [
            e1[1] * e2[2] - e1[2] * e2[1],
            e1[2] * e2[0] - e1[0] * e2[2],
            e1[0] * e2[1] - e1[1] * e2[0],
        ];
        let nn = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
        if n[2] == 0.0 || n[2].abs() <= 1e-12 * nn || !nn.is_finite() {
            return None;
        }
        Some(LTri {
            p: [[a[0], a[1]], [b[0], b[1]], [c[0], c[1]]],
            w0: a[2],
            su: -n[0] / n[2],
            sv: -n[1] / n[2],
        })
    }

    /// Depth w where the ray at (u, v) hits the triangle's plane, if (u, v) is inside the
    /// projected triangle (boundary included). Edge functions are evaluated with the edge's
    /// endpoints in a canonical order, so two triangles sharing an edge get exactly opposite
    /// values there: no ray slips through a shared edge (duplicates are removed by the caller).
    #[inline]
    pub fn hit(&self, u: f64, v: f64) -> Option<f64> {
        let q = [u, v];
        let e0 = edge(self.p[0], self.p[1], q);
        let e1 = edge(self.p[1], self.p[2], q);
        let e2 = edge(self.p[2], self.p[0], q);
        let inside = (e0 >= 0.0 && e1 >= 0.0 && e2 >= 0.0) || (e0 <= 0.0 && e1 <= 0.0 && e2 <= 0.0);
        if !inside {
            return None;
        }
        Some(self.w0 + self.su * (u - self.p[0][0]) + self.sv * (v - self.p[0][1]))
    }

    fn bounds(&self) -> [f64; 4] {
        let mut b = [
            f64::INFINITY,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::NEG_INFINITY,
        ];
        for p in &self.p {
            b[0] = b[0].min(p[0]);
            b[1] = b[1].min(p[1]);
            b[2] = b[2].max(p[0]);
            b[3] = b[3].max(p[1]);
        }
        b
    }
}

/// Signed doubled area of (a, b, q), with (a, b) put in lexicographic order first and the sign
/// restored, so `edge(a, b, q) == -edge(b, a, q)` exactly.
#[inline]
fn edge(a: [f64; 2], b: [f64; 2], q: [f64; 2]) -> f64 {
    let (p0, p1, s) = if (a[0], a[1]) <= (b[0], b[1]) {
        (a, b, 1.0)
    } else {
        (b, a, -1.0)
    };
    s * ((p1[0] - p0[0]) * (q[1] - p0[1]) - (p1[1] - p0[1]) * (q[0] - p0[0]))
}

#[derive(Clone, Copy, Debug)]
struct Node {
    bounds: [f64; 4],
    /// Leaf: first triangle index; inner: index of the left child (right = left + 1).
    start: u32,
    /// Leaf: triangle count (> 0); inner: 0.
    count: u32,
}

/// The hierarchy; triangles are reordered so every leaf holds a contiguous range.
pub struct Bvh {
    nodes: Vec<Node>,
    tris: Vec<LTri>,
}

const BINS: usize = 16;
const LEAF_MAX: usize = 4;
/// Below this depth splits are SAH, then median (depth ≤ 40 + log2 n < STACK).
const MAX_SAH_DEPTH: usize = 40;
const STACK: usize = 128;

fn area(b: &[f64; 4]) -> f64 {
    let (du, dv) = ((b[2] - b[0]).max(0.0), (b[3] - b[1]).max(0.0));
    du * dv
}
fn merge(a: &[f64; 4], b: &[f64; 4]) -> [f64; 4] {
    [
        a[0].min(b[0]),
        a[1].min(b[1]),
        a[2].max(b[2]),
        a[3].max(b[3]),
    ]
}
const EMPTY: [f64; 4] = [
    f64::INFINITY,
    f64::INFINITY,
    f64::NEG_INFINITY,
    f64::NEG_INFINITY,
];

impl Bvh {
    /// Builds the hierarchy with binned SAH (16 bins per axis, area cost, leaves ≤ 4).
    pub fn build(tris: Vec<LTri>) -> Bvh {
        let bounds: Vec<[f64; 4]> = tris.iter().map(LTri::bounds).collect();
        let centers: Vec<[f64; 2]> = bounds
            .iter()
            .map(|b| [(b[0] + b[2]) * 0.5, (b[1] + b[3]) * 0.5])
            .collect();
        let mut idx: Vec<u32> = (0..tris.len() as u32).collect();
        let mut nodes = Vec::with_capacity(2 * tris.len() / LEAF_MAX + 1);
        nodes.push(Node {
            bounds: EMPTY,
            start: 0,
            count: 0,
        });
        // explicit stack of (node index, range)
        let mut stack = vec![(0usize, 0usize, idx.len(), 0usize)];
        while let Some((ni, lo, hi, depth)) = stack.pop() {
            let nb = idx[lo..hi]
                .iter()
                .fold(EMPTY, |acc, &i| merge(&acc, &bounds[i as usize]));
            nodes[ni].bounds = nb;
            let n = hi - lo;
            let split = if n <= LEAF_MAX {
                None
            } else if depth >= MAX_SAH_DEPTH {
                // keep the tree shallow (traversal stack bound): median split
                Some((0, f64::NAN))
            } else {
                best_split(&idx[lo..hi], &bounds, &centers, &nb)
            };
            match split {
                None => {
                    nodes[ni].start = lo as u32;
                    nodes[ni].count = n as u32;
                }
                Some((axis, pos)) => {
                    let mut i = lo;
                    let mut j = hi;
                    while i < j {
                        if centers[idx[i] as usize][axis] < pos {
                            i += 1;
                        } else {
                            j -= 1;
                            idx.swap(i, j);
                        }
                    }
                    let mid = if i == lo || i == hi { lo + n / 2 } else { i };
                    let left = nodes.len();
                    for _ in 0..2 {
                        nodes.push(Node {
                            bounds: EMPTY,
                            start: 0,
                            count: 0,
                        });
                    }
                    nodes[ni].start = left as u32;
                    nodes[ni].count = 0;
                    stack.push((left, lo, mid, depth + 1));
                    stack.push((left + 1, mid, hi, depth + 1));
                }
            }
        }
        let tris = idx.iter().map(|&i| tris[i as usize]).collect();
        Bvh { nodes, tris }
    }

    /// Calls `f(triangle, w)` for every triangle hit by the ray at (u, v).
    #[inline]
    pub fn for_each_hit(&self, u: f64, v: f64, mut f: impl FnMut(&LTri, f64)) {
        if self.tris.is_empty() {
            return;
        }
        let mut stack = [0u32; STACK];
        let mut sp = 1;
        while sp > 0 {
            sp -= 1;
            let node = &self.nodes[stack[sp] as usize];
            let b = &node.bounds;
            if u < b[0] || u > b[2] || v < b[1] || v > b[3] {
                continue;
            }
            if node.count > 0 {
                let s = node.start as usize;
                for t in &self.tris[s..s + node.count as usize] {
                    if let Some(w) = t.hit(u, v) {
                        f(t, w);
                    }
                }
            } else {
                stack[sp] = node.start;
                stack[sp + 1] = node.start + 1;
                sp += 2;
            }
        }
    }
}

/// Best SAH split (axis, centre position) or `None` if a leaf is cheaper.
fn best_split(
    idx: &[u32],
    bounds: &[[f64; 4]],
    centers: &[[f64; 2]],
    nb: &[f64; 4],
) -> Option<(usize, f64)> {
    let mut cb = EMPTY;
    for &i in idx {
        let c = centers[i as usize];
        cb = merge(&cb, &[c[0], c[1], c[0], c[1]]);
    }
    let parent = area(nb).max(1e-300);
    let leaf_cost = idx.len() as f64;
    let mut best: Option<(f64, usize, f64)> = None;
    for axis in 0..2 {
        let (lo, hi) = (cb[axis], cb[axis + 2]);
        if hi - lo <= 0.0 {
            continue;
        }
        let mut bins = [(EMPTY, 0usize); BINS];
        let scale = BINS as f64 / (hi - lo);
        for &i in idx {
            let k = (((centers[i as usize][axis] - lo) * scale) as usize).min(BINS - 1);
            bins[k].0 = merge(&bins[k].0, &bounds[i as usize]);
            bins[k].1 += 1;
        }
        // suffix sweeps
        let mut right = [(EMPTY, 0usize); BINS];
        let mut acc = (EMPTY, 0usize);
        for k in (1..BINS).rev() {
            acc = (merge(&acc.0, &bins[k].0), acc.1 + bins[k].1);
            right[k] = acc;
        }
        let mut left = (EMPTY, 0usize);
        for k in 0..BINS - 1 {
            left = (merge(&left.0, &bins[k].0), left.1 + bins[k].1);
            let r = right[k + 1];
            if left.1 == 0 || r.1 == 0 {
                continue;
            }
            let cost = 0.5 + (area(&left.0) * left.1 as f64 + area(&r.0) * r.1 as f64) / parent;
            if best.is_none_or(|b| cost < b.0) {
                best = Some((cost, axis, lo + (k + 1) as f64 / scale));
            }
        }
    }
    match best {
        Some((cost, axis, pos)) if cost < leaf_cost || idx.len() > 4 * LEAF_MAX => {
            Some((axis, pos))
        }
        _ if idx.len() > 4 * LEAF_MAX => {
            // all centres coincide: median split keeps the tree shallow
            let axis = if nb[2] - nb[0] >= nb[3] - nb[1] { 0 } else { 1 };
            Some((axis, f64::NAN))
        }
        _ => None,
    }
}
