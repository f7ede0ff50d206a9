use super::*;

fn pose(position: DVec3, fov: f64) -> Pose {
    Pose {
        position,
        look_at: DVec3::new(0.0, 0.0, -5.0),
        up: DVec3::Y,
        fov,
    }
}

fn key(time: f64, x: f64, fov: f64) -> Key {
    Key {
        time,
        pose: pose(DVec3::new(x, x * x, 0.0), fov),
        ease: Ease::Pass,
        aperture: 0.0,
        focus_distance: None,
    }
}

fn timeline(keys: Vec<Key>, interpolation: Interpolation) -> Timeline {
    keyed(keys, interpolation, Speed::Keys)
}

fn keyed(keys: Vec<Key>, interpolation: Interpolation, speed: Speed) -> Timeline {
    Timeline {
        fps: 24.0,
        frame_count: 100,
        path: Path::Keys(Box::new(Keyed::new(keys, interpolation, speed))),
        clock: Default::default(),
        motion: Vec::new(),
    }
}

fn four_keys() -> Vec<Key> {
    vec![
        key(0.0, 0.0, 90.0),
        key(1.0, 1.0, 60.0),
        key(2.5, 3.0, 80.0),
        key(4.0, -1.0, 50.0),
    ]
}

#[test]
fn every_key_is_hit_exactly() {
    let keys = four_keys();
    for interp in [Interpolation::Linear, Interpolation::Smooth] {
        let tl = timeline(keys.clone(), interp);
        for k in &keys {
            assert_eq!(tl.camera_at(k.time), k.pose, "{interp:?} at {}", k.time);
        }
    }
}

#[test]
fn paths_are_continuous() {
    let keys = four_keys();
    for interp in [Interpolation::Linear, Interpolation::Smooth] {
        let tl = timeline(keys.clone(), interp);
        let dt = 1e-4;
        let mut t = 0.0;
        while t < 4.0 {
            let (a, b) = (tl.camera_at(t), tl.camera_at(t + dt));
            assert!(
                a.position.distance(b.position) < 1e-2,
                "{interp:?} jump at {t}"
            );
            assert!((a.fov - b.fov).abs() < 1e-1, "{interp:?} fov jump at {t}");
            t += dt;
        }
    }
}

#[test]
fn smooth_speed_is_continuous_at_keys() {
    let tl = timeline(four_keys(), Interpolation::Smooth);
    for t in [1.0, 2.5] {
        let (before, at, after) = (tl.speed_at(t - 1e-9), tl.speed_at(t), tl.speed_at(t + 1e-9));
        assert!(at > 0.0);
        assert!((before - at).abs() < 1e-6 * at, "{before} {at}");
        assert!((after - at).abs() < 1e-6 * at, "{after} {at}");
        // The speed is the rate of the position: a central difference agrees.
        let h = 1e-6;
        let d = tl.camera_at(t + h).position - tl.camera_at(t - h).position;
        assert!((d.length() / (2.0 * h) - at).abs() < 1e-5 * at);
    }
}

#[test]
fn a_stop_halts_every_track() {
    let mut keys = four_keys();
    keys[1].ease = Ease::Stop;
    let tl = timeline(keys.clone(), Interpolation::Smooth);
    assert_eq!(tl.speed_at(1.0), 0.0);
    let (a, b) = (tl.camera_at(1.0 - 1e-4), tl.camera_at(1.0 + 1e-4));
    assert!(a.position.distance(keys[1].pose.position) < 1e-6);
    assert!(b.position.distance(keys[1].pose.position) < 1e-6);
    assert!((a.fov - 60.0).abs() < 1e-5 && (b.fov - 60.0).abs() < 1e-5);
}

#[test]
fn coincident_points_hold_still() {
    let mut keys = vec![
        key(0.0, 1.0, 90.0),
        key(1.0, 1.0, 90.0),
        key(2.0, 2.0, 90.0),
    ];
    keys[1].pose.position = keys[0].pose.position;
    keys[1].pose.look_at = DVec3::new(1.0, 0.0, -5.0);
    let tl = timeline(keys.clone(), Interpolation::Smooth);
    assert_eq!(tl.camera_at(0.5).position, keys[0].pose.position);
    assert_eq!(tl.speed_at(0.5), 0.0);
    assert_eq!(tl.speed_at(1.0), 0.0);
    assert!(tl.camera_at(1.5).position.is_finite());
    assert!(tl.camera_at(0.5).look_at.x > 0.0);
}

#[test]
fn degenerate_keys_give_finite_poses() {
    let still = vec![
        key(0.0, 1.0, 90.0),
        key(1.0, 1.0, 90.0),
        key(2.0, 1.0, 90.0),
    ];
    let close = vec![
        key(0.0, 0.0, 90.0),
        key(1e-12, 1.0, 60.0),
        key(2e-12, 2.0, 50.0),
        key(1.0, -3.0, 70.0),
    ];
    let far: Vec<Key> = (0..4)
        .map(|i| {
            let mut k = key(i as f64, 0.0, 90.0);
            k.pose.position = DVec3::new(1e100 * (i % 2) as f64, -1e99, 1e100 * i as f64 / 3.0);
            k.pose.look_at = DVec3::new(-1e100, 1e100, 0.5);
            k
        })
        .collect();
    let back = vec![
        key(0.0, 0.0, 90.0),
        key(1.0, 1.0, 90.0),
        key(2.0, 0.0, 90.0),
    ];
    for keys in [still, close, far, back] {
        for interp in [Interpolation::Linear, Interpolation::Smooth] {
            for speed in [Speed::Keys, Speed::Constant] {
                let tl = keyed(keys.clone(), interp, speed);
                for i in 0..=400 {
                    let t = -0.5 + 3.0 * i as f64 / 400.0;
                    let p = tl.camera_at(t);
                    let v = [p.position, p.look_at, p.up];
                    assert!(v.iter().all(|v| v.is_finite()) && p.fov.is_finite(), "{t}");
                    assert!(tl.speed_at(t).is_finite());
                }
            }
        }
    }
}

#[test]
fn turning_straight_back_stops_there() {
    let keys = vec![
        key(0.0, 0.0, 90.0),
        key(1.0, 2.0, 90.0),
        key(2.0, 0.0, 90.0),
    ];
    let tl = timeline(keys, Interpolation::Smooth);
    assert_eq!(tl.speed_at(1.0), 0.0);
    assert!(tl.speed_at(0.5) > 0.0);
}

#[test]
fn constant_speed_passes_keys_by_distance() {
    // Along the x axis, 1 then 3 units: the middle key is passed a quarter of the way.
    let mut keys = vec![
        key(0.0, 0.0, 90.0),
        key(3.0, 1.0, 60.0),
        key(4.0, 4.0, 90.0),
    ];
    for k in &mut keys {
        k.pose.position.y = 0.0;
    }
    let tl = keyed(keys, Interpolation::Smooth, Speed::Constant);
    let Path::Keys(k) = &tl.path else { panic!() };
    assert_eq!((k.passes[0], k.passes[2]), (0.0, 4.0));
    assert!((k.passes[1] - 1.0).abs() < 1e-12, "{:?}", k.passes);
    assert!((tl.speed_at(0.3) - 1.0).abs() < 1e-12);
    assert!((tl.camera_at(2.0).position.x - 2.0).abs() < 1e-12);
    assert!((tl.camera_at(1.0).fov - 60.0).abs() < 1e-12);
}

#[test]
fn orbit_has_constant_radius_and_speed_and_loops() {
    let o = Orbit {
        center: DVec3::new(-0.1, 0.0, -0.6),
        radius: 1.6,
        height: 0.35,
        start_angle: 30.0,
        turns: 1.0,
        duration: 6.0,
        look_at: DVec3::ZERO,
        up: DVec3::Y,
        fov: 90.0,
        aperture: 0.0,
        focus_distance: None,
    };
    let tl = Timeline {
        fps: 24.0,
        frame_count: 144,
        path: Path::Orbit(o),
        clock: Default::default(),
        motion: Vec::new(),
    };
    let step = tl.pose_of(1).position.distance(tl.pose_of(0).position);
    for n in 0..144 {
        let p = tl.pose_of(n).position - o.center;
        assert!((DVec3::new(p.x, 0.0, p.z).length() - 1.6).abs() < 1e-12);
        assert!((p.y - 0.35).abs() < 1e-12);
        let next = tl.pose_of(n + 1).position;
        assert!((next.distance(tl.pose_of(n).position) - step).abs() < 1e-12);
    }
    // Frame 144 would be the first pose again: the loop is seamless.
    assert!(tl.pose_of(144).position.distance(tl.pose_of(0).position) < 1e-12);
    assert!((tl.speed_at(1.0) - std::f64::consts::TAU * 1.6 / 6.0).abs() < 1e-12);
}

#[test]
fn frame_time_is_exact_far_out() {
    let tl = Timeline {
        fps: 60.0,
        ..Timeline::still(key(0.0, 0.0, 90.0))
    };
    assert_eq!(tl.time_of(10_000_000), 10_000_000.0 / 60.0);
    assert_eq!(tl.time_of(600), 10.0);
}

#[test]
fn first_frame_and_fractional_fps() {
    let mut tl = Timeline {
        fps: 24000.0 / 1001.0,
        ..Timeline::still(key(0.0, 0.0, 90.0))
    };
    tl.clock.first_frame = 1001;
    tl.clock.fraction = Some((24000, 1001));
    assert_eq!(tl.time_of(1001), 0.0);
    // (n − first)·den/num with one rounding: 24 frames at 23.976 fps take 1.001 s.
    assert_eq!(tl.time_of(1025), 1.001);
    assert_eq!(tl.time_of(1001 + 24000), 1001.0);
    assert_eq!((tl.first_frame(), tl.last_frame()), (1001, 1001));
    assert_eq!(tl.fps_text(), "24000/1001");
}

#[test]
fn late_keys_interpolate() {
    let keys = vec![key(1e6, 0.0, 90.0), key(1e6 + 2.0, 2.0, 90.0)];
    let tl = timeline(keys, Interpolation::Linear);
    let p = tl.camera_at(1e6 + 1.0).position;
    assert!((p.x - 1.0).abs() < 1e-9, "{p}");
}

#[test]
fn the_film_ends_on_the_last_key() {
    assert_eq!(frames_to(4.0, 24.0), 97.0);
    assert_eq!(frames_to(0.0, 24.0), 1.0);
    assert_eq!(frames_to(-2.0, 24.0), 1.0);
    // 0.3 s × 10 fps rounds to 3.0000000000000004 frames: still frame 3.
    assert_eq!(frames_to(0.3, 10.0), 4.0);
    // Between frames: one more frame, which shows the last key held.
    assert_eq!(frames_to(1.01, 24.0), 26.0);
}
