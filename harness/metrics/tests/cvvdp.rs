//! ColorVideoVDP responds as a viewer would: JOD falls as injected flicker grows and as blur
//! widens, flicker shows up in the transient channel and blur does not, identical sequences score
//! 10, shots are scored apart, and bad input is refused with a clear error.

use tessera_metrics::*;

const W: u32 = 96;
const H: u32 = 64;
const FPS: f64 = 30.0;

/// A static, rendered-like frame: a gradient, hard-edged boxes and a fine checker.
fn scene() -> Vec<[f32; 3]> {
    let mut px = Vec::with_capacity((W * H) as usize);
    for y in 0..H {
        for x in 0..W {
            let (u, v) = (x as f32 / W as f32, y as f32 / H as f32);
            let mut c = [0.25 + 0.4 * v, 0.35 + 0.3 * u, 0.6 - 0.3 * v];
            if (20..44).contains(&x) && (16..40).contains(&y) {
                c = [0.8, 0.3, 0.2];
            }
            if y > 44 && (x / 4 + y / 4) % 2 == 0 {
                c = [0.9, 0.9, 0.85];
            }
            px.push(c);
        }
    }
    px
}

fn encode(px: &[[f32; 3]]) -> Rgb8Image {
    let data = px
        .iter()
        .flat_map(|c| c.map(|v| (v.clamp(0.0, 1.0) * 255.0).round() as u8))
        .collect();
    Rgb8Image {
        width: W,
        height: H,
        data,
    }
}

/// A separable box blur of radius `r` pixels (clamped borders).
fn blur(px: &[[f32; 3]], r: i32) -> Vec<[f32; 3]> {
    let (w, h) = (W as i32, H as i32);
    let at =
        |p: &[[f32; 3]], x: i32, y: i32| p[(y.clamp(0, h - 1) * w + x.clamp(0, w - 1)) as usize];
    let pass = |p: &[[f32; 3]], dx: i32, dy: i32| -> Vec<[f32; 3]> {
        let mut out = Vec::with_capacity(p.len());
        for y in 0..h {
            for x in 0..w {
                let mut s = [0.0; 3];
                for k in -r..=r {
                    let c = at(p, x + k * dx, y + k * dy);
                    for i in 0..3 {
                        s[i] += c[i] / (2 * r + 1) as f32;
                    }
                }
                out.push(s);
            }
        }
        out
    };
    pass(&pass(px, 1, 0), 0, 1)
}

fn run(reference: &[Rgb8Image], test: &[Rgb8Image]) -> CvvdpResult {
    let settings = CvvdpSettings {
        fps: FPS,
        ..CvvdpSettings::default()
    };
    cvvdp(Frames::Srgb(reference), Frames::Srgb(test), &settings).unwrap()
}

fn reference(n: usize) -> Vec<Rgb8Image> {
    vec![encode(&scene()); n]
}

/// Alternate frames brighter and darker by `amplitude` (relative, in encoded values).
fn flicker(n: usize, amplitude: f32) -> Vec<Rgb8Image> {
    let base = scene();
    (0..n)
        .map(|f| {
            let s = if f % 2 == 0 {
                1.0 + amplitude
            } else {
                1.0 - amplitude
            };
            encode(&base.iter().map(|c| c.map(|v| v * s)).collect::<Vec<_>>())
        })
        .collect()
}

#[test]
fn identical_sequences_score_10() {
    let r = run(&reference(6), &reference(6));
    assert_eq!(r.jod, 10.0);
    assert_eq!(r.flicker_jod, Some(10.0));
    assert_eq!(r.transient_share, Some(0.0));
    assert_eq!(r.frame_jod, vec![10.0; 6]);
    assert_eq!(r.frame_flicker_jod, vec![10.0; 6]);
    assert_eq!(r.frame_transient_share, vec![0.0; 6]);
}

#[test]
fn jod_falls_monotonically_with_flicker_amplitude() {
    let r = reference(8);
    let scores: Vec<CvvdpResult> = [0.01, 0.02, 0.03, 0.04, 0.05]
        .iter()
        .map(|&a| run(&r, &flicker(8, a)))
        .collect();
    let jod: Vec<f64> = scores.iter().map(|s| s.jod).collect();
    let shares: Vec<f64> = scores.iter().map(|s| s.transient_share.unwrap()).collect();
    eprintln!("flicker 1..5 %: JOD {jod:?}, transient share {shares:?}");
    for pair in jod.windows(2) {
        assert!(pair[1] < pair[0], "JOD must fall as flicker grows: {jod:?}");
    }
    assert!(jod[0] < 10.0 && jod[4] < 9.0, "{jod:?}");
    let flicker_jod: Vec<f64> = scores.iter().map(|s| s.flicker_jod.unwrap()).collect();
    for pair in flicker_jod.windows(2) {
        assert!(
            pair[1] < pair[0],
            "flicker JOD must fall too: {flicker_jod:?}"
        );
    }
    for s in &scores {
        let share = s.transient_share.unwrap();
        assert!(
            share > 0.5,
            "alternating flicker is mostly transient: {share}"
        );
    }
}

#[test]
fn jod_falls_monotonically_with_blur_radius_and_blur_is_not_flicker() {
    let r = reference(8);
    let base = scene();
    let scores: Vec<CvvdpResult> = [1, 2, 3, 5]
        .iter()
        .map(|&radius| run(&r, &vec![encode(&blur(&base, radius)); 8]))
        .collect();
    let jod: Vec<f64> = scores.iter().map(|s| s.jod).collect();
    let shares: Vec<f64> = scores.iter().map(|s| s.transient_share.unwrap()).collect();
    eprintln!("blur radius 1, 2, 3, 5: JOD {jod:?}, transient share {shares:?}");
    for pair in jod.windows(2) {
        assert!(pair[1] < pair[0], "JOD must fall as blur widens: {jod:?}");
    }
    for s in &scores {
        let share = s.transient_share.unwrap();
        assert!(share < 0.01, "a steady blur has no transient part: {share}");
        assert!(s.flicker_jod.unwrap() > 9.99, "{:?}", s.flicker_jod);
    }
}

#[test]
fn a_cut_scores_each_shot_and_one_shot_is_the_whole() {
    let r = reference(8);
    let mut t = reference(4);
    t.extend(flicker(4, 0.04));
    let whole = run(&r, &t);
    assert_eq!(whole.shots.len(), 1);
    assert_eq!(whole.frame_jod.len(), 8);
    let settings = CvvdpSettings {
        fps: FPS,
        cuts: vec![4],
        ..CvvdpSettings::default()
    };
    let cut = cvvdp(Frames::Srgb(&r), Frames::Srgb(&t), &settings).unwrap();
    assert_eq!(cut.shots.len(), 2);
    assert_eq!((cut.shots[1].first_frame, cut.shots[1].frames), (4, 4));
    assert_eq!(cut.shots[0].jod, 10.0, "the first shot is identical");
    assert!(cut.shots[1].jod < 9.5, "{:?}", cut.shots);
    // Pooling the shots sits between them, and the second shot alone matches its own run.
    eprintln!(
        "cut: {:?} pooled {} (one shot: {})",
        cut.shots, cut.jod, whole.jod
    );
    assert!(cut.jod < 10.0 && cut.jod > cut.shots[1].jod, "{}", cut.jod);
    let alone = run(&r[4..], &t[4..]);
    assert!((alone.jod - cut.shots[1].jod).abs() < 1e-9);
    assert!(cut.frame_jod[..4].iter().all(|&j| j == 10.0));
}

#[test]
fn maps_come_for_the_frames_asked_for() {
    let r = reference(4);
    let t = flicker(4, 0.05);
    let settings = CvvdpSettings {
        fps: FPS,
        map_frames: vec![3, 1],
        ..CvvdpSettings::default()
    };
    let res = cvvdp(Frames::Srgb(&r), Frames::Srgb(&t), &settings).unwrap();
    let frames: Vec<usize> = res.maps.iter().map(|m| m.frame).collect();
    assert_eq!(frames, [1, 3]);
    let m = &res.maps[1];
    assert_eq!(m.values.len(), (W * H) as usize);
    assert!(m.values.iter().any(|&v| v > 0.0));
    let heat = cvvdp_heatmap(m);
    assert_eq!(
        (heat.width, heat.height, heat.data.len()),
        (W, H, (W * H * 3) as usize)
    );
}

#[test]
fn hdr_linear_frames_are_compared_in_absolute_luminance() {
    let base = scene();
    let hdr = |s: f32| HdrImage {
        width: W,
        height: H,
        data: base.iter().flat_map(|c| c.map(|v| v * v * s)).collect(),
    };
    let r = vec![hdr(4.0); 4];
    let t: Vec<HdrImage> = (0..4)
        .map(|f| hdr(if f % 2 == 0 { 4.2 } else { 3.8 }))
        .collect();
    let settings = CvvdpSettings {
        fps: FPS,
        display: DisplaySpec::Named("standard_hdr_linear".into()),
        ..CvvdpSettings::default()
    };
    let white = DEFAULT_HDR_WHITE;
    let res = cvvdp(
        Frames::Linear { frames: &r, white },
        Frames::Linear { frames: &t, white },
        &settings,
    )
    .unwrap();
    assert!(res.jod < 9.5, "{}", res.jod);
    assert_eq!(res.peak_luminance, 1500.0);
}

#[test]
fn bad_input_is_refused_with_what_is_allowed() {
    let r = reference(4);
    let s = CvvdpSettings::default();
    let e = cvvdp(Frames::Srgb(&r), Frames::Srgb(&r[..3]), &s).unwrap_err();
    assert!(
        e.to_string().contains("reference has 4 frames, test has 3"),
        "{e}"
    );
    let bad_cut = CvvdpSettings {
        cuts: vec![4],
        ..CvvdpSettings::default()
    };
    let e = cvvdp(Frames::Srgb(&r), Frames::Srgb(&r), &bad_cut).unwrap_err();
    assert!(e.to_string().contains("camera cut"), "{e}");
    let bad_fps = CvvdpSettings {
        fps: 0.0,
        ..CvvdpSettings::default()
    };
    let e = cvvdp(Frames::Srgb(&r), Frames::Srgb(&r), &bad_fps).unwrap_err();
    assert!(e.to_string().contains("fps"), "{e}");
    let tiny = vec![Rgb8Image::filled(3, 3, [1, 2, 3]); 2];
    let e = cvvdp(Frames::Srgb(&tiny), Frames::Srgb(&tiny), &s).unwrap_err();
    assert!(e.to_string().contains("at least 4x4"), "{e}");
    let other = vec![Rgb8Image::filled(W, H + 1, [1, 2, 3]); 4];
    let e = cvvdp(Frames::Srgb(&r), Frames::Srgb(&other), &s).unwrap_err();
    assert!(e.to_string().contains("sizes differ"), "{e}");
}
