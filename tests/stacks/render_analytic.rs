//! The ray caster on analytic scenes: depths, layer counts and slopes against closed forms, and
//! the BVH against brute-force world-space ray–triangle intersection (Möller–Trumbore).

use crate::common::geom::{cross, dot, normalize, sub, V};
use momentlab::render::scene::{boxed, quad};
use momentlab::render::{render_view, Scene, Tri, DEDUP_EPS, MARGIN};
use momentlab::stack::{validate, DepthStack};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// World-space origin (on the near plane) of texel (x, y)'s ray, from the sidecar fields only.
fn ray_origin(st: &DepthStack, x: usize, y: usize) -> V {
    let m = &st.meta;
    let u = m.uv_origin[0] + (x as f64 + 0.5) * m.texel_size;
    let v = m.uv_origin[1] + (y as f64 + 0.5) * m.texel_size;
    std::array::from_fn(|k| u * m.u_axis[k] + v * m.v_axis[k] + m.near * m.light_dir[k])
}

fn scene(tris: Vec<Tri>, dir: V) -> Scene {
    Scene::new("test", tris, vec![("l".into(), dir)]).unwrap()
}

fn plane_y(y: f64, half: f64) -> Vec<Tri> {
    let mut t = Vec::new();
    quad(
        &mut t,
        [-half, y, -half],
        [-half, y, half],
        [half, y, half],
        [half, y, -half],
    );
    t
}

/// Layer count of texel t.
fn layers(st: &DepthStack, t: usize) -> usize {
    st.layer_count_at(t)
}

#[test]
fn plane_straight_down_exact_depth_and_coverage() {
    // A single plane perpendicular to the light: zero depth range, so the range falls back to
    // the (u,v) extent 2; the plane sits at z = 0.5 exactly, slopes 0.
    let st = render_view(&scene(plane_y(0.0, 1.0), [0.0, -1.0, 0.0]), 0, 64);
    validate(&st).unwrap();
    assert_eq!(st.meta.layers, 1);
    assert!((st.meta.near - (-MARGIN * 2.0)).abs() < 1e-12);
    assert!((st.meta.far - MARGIN * 2.0).abs() < 1e-12);
    let mut covered = 0;
    for y in 0..64 {
        for x in 0..64 {
            let t = y * 64 + x;
            let o = ray_origin(&st, x, y);
            let inside = o[0].abs() <= 1.0 && o[2].abs() <= 1.0;
            assert_eq!(layers(&st, t), inside as usize, "texel {x},{y}");
            if inside {
                covered += 1;
                assert_eq!(st.depth[0][t], 0.5);
                assert_eq!(st.dzdu[0][t], 0.0);
                assert_eq!(st.dzdv[0][t], 0.0);
            }
        }
    }
    // the window is 2·1.02 wide: 64/1.02 ≈ 62.7 texels across → 62 or 63 per axis
    assert!((62 * 62..=64 * 64).contains(&covered), "{covered}");
}

#[test]
fn box_two_layers_with_exact_depths() {
    // Unit-height box [-0.5,0.5]×[0,1]×[-0.5,0.5] on nothing else, light straight down:
    // w = −y ∈ [−1, 0], near = −1 − 0.01, far = 0.01; top at z = 0.01/1.02, bottom 1.01/1.02.
    let mut tris = Vec::new();
    boxed(&mut tris, [-0.5, 0.0, -0.5], [0.5, 1.0, 0.5]);
    let st = render_view(&scene(tris, [0.0, -1.0, 0.0]), 0, 32);
    validate(&st).unwrap();
    assert!((st.meta.near + 1.0 + MARGIN).abs() < 1e-12);
    assert!((st.meta.far - MARGIN).abs() < 1e-12);
    let (ztop, zbot) = (
        (MARGIN / (1.0 + 2.0 * MARGIN)) as f32,
        ((1.0 + MARGIN) / (1.0 + 2.0 * MARGIN)) as f32,
    );
    let mut n2 = 0;
    for t in 0..32 * 32 {
        let (x, y) = (t % 32, t / 32);
        let o = ray_origin(&st, x, y);
        if o[0].abs() < 0.5 && o[2].abs() < 0.5 {
            n2 += 1;
            assert_eq!(layers(&st, t), 2);
            assert_eq!(st.depth[0][t], ztop);
            assert_eq!(st.depth[1][t], zbot);
        } else if o[0].abs() > 0.5 || o[2].abs() > 0.5 {
            assert_eq!(layers(&st, t), 0);
        }
    }
    assert!(n2 > 800, "{n2}");
}

#[test]
fn oblique_box_matches_slab_intersection() {
    // Box under an oblique light: every texel against the analytic slab method.
    let (lo, hi) = ([-1.0, 0.0, -0.5], [1.0, 0.7, 0.5]);
    let mut tris = Vec::new();
    boxed(&mut tris, lo, hi);
    let dir = normalize([0.3, -0.8, 0.5]);
    let res = 96;
    let st = render_view(&scene(tris, dir), 0, res);
    validate(&st).unwrap();
    let range = st.meta.far - st.meta.near;
    let mut checked = 0;
    for y in 0..res {
        for x in 0..res {
            let t = y * res + x;
            let o = ray_origin(&st, x, y);
            let (mut t0, mut t1) = (f64::NEG_INFINITY, f64::INFINITY);
            for k in 0..3 {
                let (a, b) = ((lo[k] - o[k]) / dir[k], (hi[k] - o[k]) / dir[k]);
                t0 = t0.max(a.min(b));
                t1 = t1.min(a.max(b));
            }
            let gap = (t1 - t0) / range;
            if t0 < t1 && gap > 1e-4 {
                assert_eq!(layers(&st, t), 2, "texel {x},{y}");
                assert!((st.depth[0][t] as f64 - t0 / range).abs() < 1e-6);
                assert!((st.depth[1][t] as f64 - t1 / range).abs() < 1e-6);
                checked += 1;
            } else if t0 > t1 + 1e-6 * range {
                assert_eq!(layers(&st, t), 0, "texel {x},{y}");
            }
        }
    }
    assert!(checked > 1000, "{checked}");
}

#[test]
fn two_parallel_planes_layer_counts_and_depths() {
    // Big plane at y = 0 (half size 2), small plane at y = 1 (half size 1), light straight down.
    let mut tris = plane_y(0.0, 2.0);
    tris.extend(plane_y(1.0, 1.0));
    let st = render_view(&scene(tris, [0.0, -1.0, 0.0]), 0, 40);
    validate(&st).unwrap();
    assert_eq!(st.meta.layers, 2);
    let near = -1.0 - MARGIN;
    let range = 1.0 + 2.0 * MARGIN;
    let (z1, z0) = (
        ((-1.0 - near) / range) as f32,
        ((0.0 - near) / range) as f32,
    );
    let (mut one, mut two) = (0, 0);
    for t in 0..40 * 40 {
        let o = ray_origin(&st, t % 40, t / 40);
        let (ax, az) = (o[0].abs(), o[2].abs());
        if ax < 1.0 && az < 1.0 {
            two += 1;
            assert_eq!(layers(&st, t), 2);
            assert_eq!((st.depth[0][t], st.depth[1][t]), (z1, z0));
        } else if ax < 2.0 && az < 2.0 && (ax > 1.0 || az > 1.0) {
            one += 1;
            assert_eq!(layers(&st, t), 1);
            assert_eq!(st.depth[0][t], z0);
        }
    }
    assert!(one > 500 && two > 200, "{one} {two}");
}

#[test]
fn tilted_plane_depths_and_slopes() {
    // Plane through the origin with normal n, under several light directions: depth against
    // ray–plane intersection, slopes against the closed form and against finite differences.
    let mut rng = ChaCha8Rng::seed_from_u64(11);
    for _ in 0..6 {
        let n = normalize([rng.gen_range(-0.5..0.5), 1.0, rng.gen_range(-0.5..0.5)]);
        let a = normalize(cross(n, [0.0, 0.0, 1.0]));
        let b = cross(n, a);
        let p = |s: f64, t: f64| -> V { std::array::from_fn(|k| 2.0 * (s * a[k] + t * b[k])) };
        let mut tris = Vec::new();
        quad(&mut tris, p(-1., -1.), p(-1., 1.), p(1., 1.), p(1., -1.));
        // a small second object to give the frame a depth range
        boxed(&mut tris, [3.0, -1.0, 3.0], [3.2, 1.0, 3.2]);
        let dir = normalize([rng.gen_range(-0.6..0.6), -1.0, rng.gen_range(-0.6..0.6)]);
        let res = 64;
        let st = render_view(&scene(tris, dir), 0, res);
        validate(&st).unwrap();
        let m = &st.meta;
        let range = m.far - m.near;
        let su = -dot(n, m.u_axis) / dot(n, m.light_dir) * m.texel_size / range;
        let sv = -dot(n, m.v_axis) / dot(n, m.light_dir) * m.texel_size / range;
        let mut checked = 0;
        for y in 0..res - 1 {
            for x in 0..res - 1 {
                let o = ray_origin(&st, x, y);
                let t_hit = -dot(n, o) / dot(n, dir);
                let hp: V = std::array::from_fn(|k| o[k] + t_hit * dir[k]);
                let (s, t) = (dot(hp, a) / 2.0, dot(hp, b) / 2.0);
                let i = y * res + x;
                if s.abs() < 0.8 && t.abs() < 0.8 {
                    let z = st.depth[0][i] as f64;
                    assert!((z - t_hit / range).abs() < 1e-6, "{z} vs {}", t_hit / range);
                    assert!((st.dzdu[0][i] as f64 - su).abs() < 1e-6 * (1.0 + su.abs()));
                    assert!((st.dzdv[0][i] as f64 - sv).abs() < 1e-6 * (1.0 + sv.abs()));
                    // finite differences to the right / below neighbours on the same plane
                    let fx = st.depth[0][i + 1] as f64 - z;
                    let fy = st.depth[0][i + res] as f64 - z;
                    assert!((fx - su).abs() < 1e-6, "dz/dx {fx} vs {su}");
                    assert!((fy - sv).abs() < 1e-6, "dz/dy {fy} vs {sv}");
                    checked += 1;
                }
            }
        }
        assert!(checked > 300, "{checked}");
    }
}

/// Möller–Trumbore, f64, world space; returns t ≥ 0 along the ray (boundary counted).
fn mt(o: V, d: V, tri: &Tri) -> Option<(f64, f64)> {
    let e1 = sub(tri[1], tri[0]);
    let e2 = sub(tri[2], tri[0]);
    let p = cross(d, e2);
    let det = dot(e1, p);
    if det.abs() < 1e-14 {
        return None;
    }
    let s = sub(o, tri[0]);
    let u = dot(s, p) / det;
    let q = cross(s, e1);
    let v = dot(d, q) / det;
    let margin = u.min(v).min(1.0 - u - v);
    if margin < -1e-12 {
        return None;
    }
    Some((dot(e2, q) / det, margin))
}

#[test]
fn bvh_matches_brute_force_on_random_scenes() {
    let mut rng = ChaCha8Rng::seed_from_u64(5);
    let mut texels = 0;
    let mut skipped = 0;
    for round in 0..8 {
        // random triangles of varied size plus a closed box (shared edges)
        let mut tris: Vec<Tri> = (0..400)
            .map(|_| {
                let c: V = std::array::from_fn(|_| rng.gen_range(-3.0..3.0));
                let s = rng.gen_range(0.05..1.5);
                std::array::from_fn(|_| std::array::from_fn(|k| c[k] + rng.gen_range(-s..s)))
            })
            .collect();
        boxed(&mut tris, [-1.0, -1.0, -1.0], [1.0, 0.5, 1.5]);
        let dir = normalize(std::array::from_fn(|_| rng.gen_range(-1.0..1.0)));
        let res = 48 + round;
        let st = render_view(&scene(tris.clone(), dir), 0, res);
        validate(&st).unwrap();
        let range = st.meta.far - st.meta.near;
        for y in 0..res {
            for x in 0..res {
                let o = ray_origin(&st, x, y);
                let mut hits: Vec<(f64, f64)> = tris.iter().filter_map(|t| mt(o, dir, t)).collect();
                hits.sort_by(|a, b| a.0.total_cmp(&b.0));
                // skip rays that graze an edge or see two surfaces at almost the same depth
                let borderline = hits.iter().any(|h| h.1 < 1e-9)
                    || hits
                        .windows(2)
                        .any(|w| ((w[1].0 - w[0].0) / range - DEDUP_EPS).abs() < 1e-7);
                if borderline {
                    skipped += 1;
                    continue;
                }
                let mut want: Vec<f64> = Vec::new();
                for h in &hits {
                    let z = h.0 / range;
                    if want.last().is_none_or(|&l| z - l > DEDUP_EPS) {
                        want.push(z);
                    }
                }
                let t = y * res + x;
                assert_eq!(layers(&st, t), want.len(), "round {round} texel {x},{y}");
                for (l, z) in want.iter().enumerate() {
                    assert!((st.depth[l][t] as f64 - z).abs() < 1e-6, "layer {l}");
                }
                texels += 1;
            }
        }
    }
    assert!(texels > 15000, "{texels}");
    // box edges are hit by few texel centres; a lot of skipping would hide bugs
    assert!(skipped * 50 < texels, "{skipped} of {texels} skipped");
}

#[test]
fn closed_meshes_have_even_layer_counts() {
    // Watertightness: rays through a closed sphere/cylinder mesh (shared edges everywhere,
    // many texel centres on edges) see an even number of surfaces.
    let text = r#"{"name":"w","lights":[{"dir":[0,-1,0]},{"dir":[0.3,-0.7,0.2]},
        {"azimuth_deg":45,"elevation_deg":45}],
        "objects":[{"type":"sphere","radius":1,"segments":40},
                   {"type":"cylinder","radius":0.5,"height":1,"segments":16,
                    "transform":{"translate":[3,0,0]}},
                   {"type":"stairs","steps":5,"width":1,"step_depth":0.3,"step_height":0.2,
                    "transform":{"translate":[0,0,3]}}]}"#;
    let sc = Scene::from_json(text, &|_| unreachable!()).unwrap();
    for li in 0..3 {
        let st = render_view(&sc, li, 128);
        validate(&st).unwrap();
        let odd = (0..st.texel_count())
            .filter(|&t| layers(&st, t) % 2 == 1)
            .count();
        // only silhouette-grazing rays may be odd
        assert!(odd <= 8, "light {li}: {odd} texels with odd layer counts");
    }
}
