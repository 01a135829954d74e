//! Depth-stack files: write → read is bit-exact; every kind of bad input is rejected with a
//! message naming the file (and layer / texel); `momentlab import` exits 1 with one line.

use crate::common::{bits, momentlab, tmp};
use exr::prelude::*;
use momentlab::stack::{self, validate, DepthStack, StackMeta};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::path::Path;

fn meta(w: usize, h: usize, layers: usize) -> StackMeta {
    StackMeta {
        scene: "s".into(),
        view: "v".into(),
        light_dir: [0.0, -1.0, 0.0],
        near: -1.0,
        far: 2.0,
        width: w,
        height: h,
        layers,
        u_axis: [1.0, 0.0, 0.0],
        v_axis: [0.0, 0.0, 1.0],
        uv_origin: [-1.0, -1.0],
        texel_size: 0.25,
    }
}

/// A random valid stack: per texel 0..=layers sorted distinct depths, rest +inf.
fn random_stack(rng: &mut ChaCha8Rng, w: usize, h: usize, layers: usize) -> DepthStack {
    let n = w * h;
    let mut st = DepthStack {
        meta: meta(w, h, layers),
        depth: vec![vec![f32::INFINITY; n]; layers],
        dzdu: vec![vec![0.0; n]; layers],
        dzdv: vec![vec![0.0; n]; layers],
    };
    for t in 0..n {
        let k = rng.gen_range(0..=layers);
        let mut zs: Vec<f32> = (0..k).map(|_| rng.gen::<f32>()).collect();
        if t == 0 && k > 0 {
            zs[0] = 0.0; // extremes are allowed
        }
        if t == 1 && k > 0 {
            zs[0] = 1.0;
        }
        zs.sort_by(f32::total_cmp);
        zs.dedup();
        for (l, z) in zs.iter().enumerate() {
            st.depth[l][t] = *z;
            st.dzdu[l][t] = rng.gen_range(-1e3..1e3);
            st.dzdv[l][t] = rng.gen::<f32>() * 1e-7;
        }
    }
    st
}

#[test]
fn write_read_is_bit_exact() {
    let dir = tmp("roundtrip");
    let mut rng = ChaCha8Rng::seed_from_u64(1);
    for (i, (w, h, l)) in [(1, 1, 1), (7, 5, 3), (33, 17, 12), (64, 64, 2)]
        .into_iter()
        .enumerate()
    {
        let st = random_stack(&mut rng, w, h, l);
        validate(&st).unwrap();
        let p = dir.join(format!("s{i}.exr"));
        stack::write(&p, &st).unwrap();
        let back = stack::read(&p).unwrap();
        assert_eq!(back.meta, st.meta);
        assert_eq!(bits(&back.depth), bits(&st.depth));
        assert_eq!(bits(&back.dzdu), bits(&st.dzdu));
        assert_eq!(bits(&back.dzdv), bits(&st.dzdv));
    }
    // load_dir: all four, sorted by file name
    let all = stack::load_dir(&dir).unwrap();
    assert_eq!(all.len(), 4);
    assert_eq!(all[2].meta.width, 33);
    // a rendered view too
    let sc = momentlab::render::embedded_scenes().unwrap();
    let st = momentlab::render::render_view(&sc[2], 1, 48);
    let p = dir.join("rendered.exr");
    stack::write(&p, &st).unwrap();
    let back = stack::read(&p).unwrap();
    assert_eq!(back.meta, st.meta);
    assert_eq!(bits(&back.depth), bits(&st.depth));
    assert_eq!(bits(&back.dzdu), bits(&st.dzdu));
}

/// Writes an EXR with arbitrary channels (bypassing validation) and a sidecar text.
fn write_raw(
    path: &Path,
    w: usize,
    h: usize,
    chans: Vec<(String, FlatSamples)>,
    side: Option<&str>,
) {
    let list: SmallVec<[AnyChannel<FlatSamples>; 4]> = chans
        .into_iter()
        .map(|(n, s)| AnyChannel::new(Text::new_or_panic(n), s))
        .collect();
    let layer = Layer::new(
        (w, h),
        LayerAttributes::default(),
        Encoding::SMALL_LOSSLESS,
        AnyChannels::sort(list),
    );
    Image::from_layer(layer).write().to_file(path).unwrap();
    if let Some(s) = side {
        std::fs::write(path.with_extension("json"), s).unwrap();
    }
}

fn stack_chans(st: &DepthStack) -> Vec<(String, FlatSamples)> {
    let mut v = Vec::new();
    for l in 0..st.depth.len() {
        v.push((
            stack::channel_name(l, "Z"),
            FlatSamples::F32(st.depth[l].clone()),
        ));
        v.push((
            stack::channel_name(l, "dzdu"),
            FlatSamples::F32(st.dzdu[l].clone()),
        ));
        v.push((
            stack::channel_name(l, "dzdv"),
            FlatSamples::F32(st.dzdv[l].clone()),
        ));
    }
    v
}

fn base() -> DepthStack {
    // 4×3 texels, 2 layers; texel (1,2) has two surfaces, others one or none
    let mut st = DepthStack {
        meta: meta(4, 3, 2),
        depth: vec![vec![0.5; 12], vec![f32::INFINITY; 12]],
        dzdu: vec![vec![0.0; 12]; 2],
        dzdv: vec![vec![0.0; 12]; 2],
    };
    st.depth[0][0] = f32::INFINITY;
    st.depth[1][2 * 4 + 1] = 0.75;
    st
}

/// Writes `st` raw (no validation) with its own sidecar and returns the read error text.
fn err_of(dir: &Path, name: &str, st: &DepthStack) -> String {
    let p = dir.join(format!("{name}.exr"));
    let side = serde_json::to_string(&st.meta).unwrap();
    write_raw(
        &p,
        st.meta.width,
        st.meta.height,
        stack_chans(st),
        Some(&side),
    );
    let e = stack::read(&p).expect_err(name);
    let msg = format!("{e:#}");
    assert!(
        msg.contains(&format!("{name}.exr")),
        "no file name in: {msg}"
    );
    assert!(!msg.contains('\n'), "multi-line: {msg}");
    msg
}

#[test]
fn bad_values_are_rejected_naming_file_layer_and_texel() {
    let dir = tmp("bad_values");
    assert!(validate(&base()).is_ok());

    let mut st = base();
    st.depth[0][2 * 4 + 3] = f32::NAN;
    let m = err_of(&dir, "nan", &st);
    assert!(m.contains("layer 0 texel (x=3, y=2): depth is NaN"), "{m}");

    let mut st = base();
    st.depth[0][4 + 2] = 1.5;
    let m = err_of(&dir, "above", &st);
    assert!(
        m.contains("layer 0 texel (x=2, y=1): depth 1.5 outside [0,1]"),
        "{m}"
    );

    let mut st = base();
    st.depth[0][4 + 2] = -0.25;
    let m = err_of(&dir, "below", &st);
    assert!(
        m.contains("(x=2, y=1)") && m.contains("outside [0,1]"),
        "{m}"
    );

    let mut st = base();
    st.depth[0][1] = f32::NEG_INFINITY;
    let m = err_of(&dir, "neginf", &st);
    assert!(
        m.contains("(x=1, y=0)") && m.contains("outside [0,1]"),
        "{m}"
    );

    let mut st = base();
    st.depth[1][2 * 4 + 1] = 0.5; // equal to layer 0
    let m = err_of(&dir, "equal", &st);
    assert!(
        m.contains("layer 1 texel (x=1, y=2)") && m.contains("not strictly increasing"),
        "{m}"
    );

    let mut st = base();
    st.depth[1][2 * 4 + 1] = 0.25; // decreasing
    let m = err_of(&dir, "decreasing", &st);
    assert!(
        m.contains("layer 1 texel (x=1, y=2)") && m.contains("not strictly increasing"),
        "{m}"
    );

    let mut st = base();
    st.depth[1][0] = 0.3; // surface after a missing one (layer 0 is +inf)
    let m = err_of(&dir, "gap", &st);
    assert!(
        m.contains("layer 1 texel (x=0, y=0)") && m.contains("+inf"),
        "{m}"
    );

    let mut st = base();
    st.dzdv[1][5] = f32::INFINITY;
    let m = err_of(&dir, "slope", &st);
    assert!(m.contains("layer 1 texel (x=1, y=1): slope dzdv"), "{m}");

    let mut st = base();
    st.meta.near = 3.0;
    let m = err_of(&dir, "nearfar", &st);
    assert!(m.contains("near/far"), "{m}");

    let mut st = base();
    st.meta.light_dir = [0.0, -2.0, 0.0];
    let m = err_of(&dir, "lightdir", &st);
    assert!(m.contains("unit vector"), "{m}");
}

#[test]
fn bad_files_are_rejected() {
    let dir = tmp("bad_files");
    let st = base();
    let side = serde_json::to_string(&st.meta).unwrap();
    let read_err = |p: &Path| {
        let m = format!("{:#}", stack::read(p).unwrap_err());
        assert!(m.contains(&p.display().to_string()), "{m}");
        m
    };

    // missing sidecar
    let p = dir.join("noside.exr");
    write_raw(&p, 4, 3, stack_chans(&st), None);
    assert!(read_err(&p).contains("missing sidecar"));

    // malformed sidecar (bad JSON; a field missing; wrong type)
    for (i, bad) in [
        "{",
        r#"{"scene":"s"}"#,
        &side.replace("\"width\":4", "\"width\":\"4\""),
    ]
    .iter()
    .enumerate()
    {
        let p = dir.join(format!("badside{i}.exr"));
        write_raw(&p, 4, 3, stack_chans(&st), Some(bad));
        assert!(read_err(&p).contains("malformed sidecar"));
    }

    // sidecar / EXR disagreement: size, more layers in the sidecar, fewer
    let p = dir.join("size.exr");
    write_raw(
        &p,
        4,
        3,
        stack_chans(&st),
        Some(&side.replace("\"width\":4", "\"width\":5")),
    );
    assert!(read_err(&p).contains("EXR is 4x3 but the sidecar says 5x3"));
    let p = dir.join("morelayers.exr");
    write_raw(
        &p,
        4,
        3,
        stack_chans(&st),
        Some(&side.replace("\"layers\":2", "\"layers\":3")),
    );
    assert!(read_err(&p).contains("channel 'layer002.Z' missing"));
    let p = dir.join("fewerlayers.exr");
    write_raw(
        &p,
        4,
        3,
        stack_chans(&st),
        Some(&side.replace("\"layers\":2", "\"layers\":1")),
    );
    assert!(read_err(&p).contains("beyond the sidecar's layer count 1"));

    // a channel missing (slopes of layer 1)
    let p = dir.join("nochan.exr");
    let mut ch = stack_chans(&st);
    ch.retain(|(n, _)| n != "layer001.dzdu");
    write_raw(&p, 4, 3, ch, Some(&side));
    assert!(read_err(&p).contains("channel 'layer001.dzdu' missing"));

    // unknown channel, half-float channel
    let p = dir.join("unknown.exr");
    let mut ch = stack_chans(&st);
    ch.push(("R".into(), FlatSamples::F32(vec![0.0; 12])));
    write_raw(&p, 4, 3, ch, Some(&side));
    assert!(read_err(&p).contains("unexpected channel 'R'"));
    let p = dir.join("half.exr");
    let mut ch = stack_chans(&st);
    ch[0].1 = FlatSamples::F16(vec![f16::from_f32(0.5); 12]);
    write_raw(&p, 4, 3, ch, Some(&side));
    assert!(read_err(&p).contains("half (f16)"));

    // not an EXR at all; truncated EXR
    let p = dir.join("garbage.exr");
    std::fs::write(&p, b"this is not an openexr file").unwrap();
    std::fs::write(p.with_extension("json"), &side).unwrap();
    assert!(read_err(&p).contains("not a readable OpenEXR"));
    let good = dir.join("good.exr");
    stack::write(&good, &st).unwrap();
    let bytes = std::fs::read(&good).unwrap();
    let p = dir.join("truncated.exr");
    std::fs::write(&p, &bytes[..bytes.len() / 2]).unwrap();
    std::fs::write(p.with_extension("json"), &side).unwrap();
    assert!(read_err(&p).contains("not a readable OpenEXR"));

    // in-memory mismatched channel sizes are caught by validate (and write refuses)
    let mut bad = base();
    bad.dzdu[1].pop();
    let m = format!("{:#}", validate(&bad).unwrap_err());
    assert!(
        m.contains("layer 1 dzdu channel has 11 values, expected 4x3 = 12"),
        "{m}"
    );
    let m = format!(
        "{:#}",
        stack::write(&dir.join("refused.exr"), &bad).unwrap_err()
    );
    assert!(
        m.contains("refusing to write") && m.contains("refused.exr"),
        "{m}"
    );

    // empty directory
    let empty = tmp("empty");
    assert!(format!("{:#}", stack::load_dir(&empty).unwrap_err()).contains("no .exr"));
}

#[test]
fn import_cli_validates_copies_and_fails_with_one_line() {
    let dir = tmp("cli");
    let out = dir.join("out");
    let mut rng = ChaCha8Rng::seed_from_u64(3);
    let st = random_stack(&mut rng, 9, 7, 4);
    stack::write(&dir.join("a.exr"), &st).unwrap();
    let o = momentlab()
        .args([
            "import",
            dir.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
        ])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let copied = stack::read(&out.join("a.exr")).unwrap();
    assert_eq!(bits(&copied.depth), bits(&st.depth));

    // corrupt: NaN at texel (4, 6), layer 0
    let mut bad = st.clone();
    bad.depth[0][6 * 9 + 4] = f32::NAN;
    let p = dir.join("b.exr");
    write_raw(
        &p,
        9,
        7,
        stack_chans(&bad),
        Some(&serde_json::to_string(&bad.meta).unwrap()),
    );
    let o = momentlab()
        .args(["import", p.to_str().unwrap()])
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(1));
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(err.starts_with("error: ") && err.contains("b.exr"), "{err}");
    assert!(
        err.contains("layer 0 texel (x=4, y=6): depth is NaN"),
        "{err}"
    );
}
