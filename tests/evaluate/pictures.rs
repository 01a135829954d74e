//! Five-panel pictures: written PNG decodes to the documented panel layout and colours.

use crate::common::kernel::*;
use crate::common::technique::Mock;
use crate::common::{decode_png, tmp, tmp_path};
use momentlab::metrics::{self, Bias, Subject};
use momentlab::report::pictures::{self, BACKGROUND, GAP, GAP_PX, PANELS};

/// A technique that always says "lit" (G = 0): the error panel then shows PCF itself.
fn always_lit() -> Mock {
    Mock::new("always-lit", 1, |z, out| out[0] = z, |_, _| 0.0)
}

/// 48×32: a tilted ground plane (two layers under a floating box at x,y ∈ 16..28), and an
/// empty strip x ≥ 44.
fn scene() -> momentlab::stack::DepthStack {
    stack_from("box", 48, 32, 2, |l, x, y| {
        if x >= 44 {
            return None;
        }
        let ground = (0.7 + 0.001 * x as f64) as f32;
        let in_box = (16..28).contains(&x) && (16..28).contains(&y);
        match (l, in_box) {
            (0, true) => Some((0.2, 0.0, 0.0)),
            (0, false) => Some((ground, 0.001, 0.0)),
            (1, true) => Some((ground, 0.001, 0.0)),
            _ => None,
        }
    })
}

#[test]
fn picture_layout_and_colours() {
    let s = scene();
    let t = always_lit();
    let shadows = metrics::front_shadows(&s, Subject::Technique(&t), &Bias::default()).unwrap();
    let img = pictures::view_picture(&s, &shadows).unwrap();
    let (w, h) = (48, 32);
    assert_eq!(img.width, PANELS * w + (PANELS - 1) * GAP_PX);
    assert_eq!(img.height, h);

    let dir = tmp("pictures");
    let path = dir.join("box.png");
    pictures::write_png(&path, &img).unwrap();
    let (pw, ph, data) = decode_png(&path);
    assert_eq!((pw, ph), (img.width, img.height));
    assert_eq!(data, img.data, "PNG round trip is lossless");

    let px = |panel: usize, x: usize, y: usize| img.get(panel * (w + GAP_PX) + x, y);
    // gaps
    assert_eq!(img.get(w, 0), GAP);
    // background strip in every panel
    for p in 0..PANELS {
        assert_eq!(px(p, 46, 5), BACKGROUND);
    }
    // front depth: box (0.2) brighter than ground (≥ 0.7)
    assert!(px(0, 20, 20)[0] > px(0, 5, 5)[0]);
    assert_eq!(
        px(0, 20, 20)[0],
        ((1.0f64 - 0.2f32 as f64) * 255.0).round() as u8
    );
    // layer count differs between box (2 layers) and open ground (1)
    assert_ne!(px(1, 20, 20), px(1, 5, 5));
    // PCF: open ground far from the box is lit (white), ground right next to the box is
    // partly shadowed (the receiver is the front layer there)
    assert_eq!(px(2, 5, 5), [255, 255, 255]);
    assert!(px(2, 15, 20)[0] < 255);
    // box top is lit
    assert_eq!(px(2, 22, 22), [255, 255, 255]);
    // technique (always lit): white everywhere with a surface
    assert_eq!(px(3, 15, 20), [255, 255, 255]);
    // error panel: black where PCF = 0, coloured where PCF > 0
    assert_eq!(px(4, 5, 5), pictures::inferno(0.0));
    let pcf = shadows.pcf[20 * w + 15];
    assert!(pcf > 0.0);
    assert_eq!(px(4, 15, 20), pictures::inferno(pcf.sqrt()));
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn mismatched_shadow_maps_are_rejected() {
    let s = scene();
    let bad = metrics::FrontShadows {
        pcf: vec![0.0; 3],
        g: vec![0.0; 3],
    };
    let e = pictures::view_picture(&s, &bad).unwrap_err().to_string();
    assert!(e.contains("test/box"), "{e}");
    // A picture whose folder is a regular file: a one-line error naming the path.
    let blocker = tmp_path("png-blocker");
    std::fs::write(&blocker, b"not a folder").unwrap();
    let e = pictures::write_png(&blocker.join("x.png"), &pictures::RgbImage::new(2, 2, GAP))
        .unwrap_err();
    std::fs::remove_file(&blocker).ok();
    assert!(
        format!("{e:#}").contains(&blocker.display().to_string()),
        "{e:#}"
    );
}

#[test]
fn layer_pictures_show_the_shadow_on_the_hidden_layer() {
    let s = scene();
    let t = always_lit();
    let (w, h) = (48, 32);
    let sh = metrics::layer_shadows(&s, 1, Subject::Technique(&t), &Bias::default()).unwrap();
    let img = pictures::layer_picture(&s, 1, &sh).unwrap();
    assert_eq!(
        img.width,
        4 * w + 4 * GAP_PX + pictures::BAR_PX + pictures::BAR_LABEL_PX
    );
    assert_eq!(img.height, h);
    let px = |panel: usize, x: usize, y: usize| img.get(panel * (w + GAP_PX) + x, y);
    // Layer 1 exists only under the box: elsewhere every panel is background.
    for p in 0..4 {
        assert_eq!(px(p, 5, 5), BACKGROUND);
    }
    // Under the box's centre the ground is fully shadowed by the box: PCF black, the
    // always-lit technique white, |error| = 1 (top of the colour map).
    assert_eq!(
        px(0, 22, 22),
        pictures::depth_colour(s.depth[1][22 * w + 22] as f64)
    );
    assert_eq!(sh.pcf[22 * w + 22], 1.0);
    assert_eq!(px(1, 22, 22), [0, 0, 0]);
    assert_eq!(px(2, 22, 22), [255, 255, 255]);
    assert_eq!(px(3, 22, 22), pictures::error_colour(1.0));
    // The front layer's picture of the same texel is lit (the box top).
    let front = metrics::layer_shadows(&s, 0, Subject::Technique(&t), &Bias::default()).unwrap();
    assert_eq!(front.pcf[22 * w + 22], 0.0);
    // Colour bar: top = error 1, bottom = error 0.
    let bar_x = 4 * (w + GAP_PX) + pictures::BAR_PX - 1;
    assert_eq!(img.get(bar_x, 0), pictures::error_colour(1.0));
    assert_eq!(img.get(bar_x, h - 1), pictures::error_colour(0.0));
    // A layer the stack does not have, or maps of the wrong size, are errors.
    let e = pictures::layer_picture(&s, 2, &sh).unwrap_err().to_string();
    assert!(e.contains("test/box layer 2"), "{e}");
    let none = metrics::layer_shadows(&s, 5, Subject::Pcf, &Bias::default()).unwrap();
    assert!(none.pcf.iter().all(|v| v.is_nan()));
}

#[test]
fn one_colour_convention_for_depth_in_every_picture() {
    let s = scene();
    let (w, h) = (48, 32);
    let shadows = metrics::front_shadows(&s, Subject::Pcf, &Bias::default()).unwrap();
    let view = pictures::view_picture(&s, &shadows).unwrap();
    let prev = pictures::preview_picture(&s);
    assert_eq!((prev.width, prev.height), (2 * w + GAP_PX, h));
    // The preview is panels 1 and 2 of the light-view picture, pixel for pixel.
    for y in 0..h {
        for x in 0..w {
            assert_eq!(prev.get(x, y), view.get(x, y), "depth at {x},{y}");
            assert_eq!(
                prev.get(w + GAP_PX + x, y),
                view.get(w + GAP_PX + x, y),
                "layers at {x},{y}"
            );
        }
    }
    // Near is bright: the box top (z = 0.2) is brighter than the ground (z ≥ 0.7).
    assert!(prev.get(20, 20)[0] > prev.get(5, 5)[0] + 100);
    assert_eq!(pictures::depth_colour(0.0), [255, 255, 255]);
    assert_eq!(pictures::depth_colour(1.0), [0, 0, 0]);
    assert_eq!(pictures::depth_colour(f64::INFINITY), BACKGROUND);
    // Lit is white, shadowed black.
    assert_eq!(pictures::shadow_colour(0.0), [255, 255, 255]);
    assert_eq!(pictures::shadow_colour(1.0), [0, 0, 0]);
}
