//! What goes into one panel of the path plot, back to front.

use super::*;

pub(super) fn draw_panel(img: &mut RgbImage, p: &Panel, seq: &Sequence, plot: &Plot) {
    let mut c = Canvas::new(img, p.rect());
    c.fill(PANEL);
    draw_solids(&mut c, p, seq, plot);
    draw_grid(&mut c, p);
    draw_spheres(&mut c, p, seq, plot);
    draw_target_links(&mut c, p, plot);
    draw_moving(&mut c, p, plot);
    draw_path(&mut c, p, plot);
    draw_ticks(&mut c, p, plot);
    draw_targets(&mut c, p, plot);
    draw_lights(&mut c, p, seq);
    draw_ends(&mut c, p, plot);
    // Last, so labels of far-off targets and lights never hide a keyframe.
    draw_keys(&mut c, p, plot);
    draw_gizmo(&mut c, p);
    c.frame_rect(p.rect(), BORDER);
}

/// Planes and giant spheres, as the solid region they cut from the slice plane, tinted with
/// their material; a camera inside one is obvious.
pub(super) fn draw_solids(c: &mut Canvas, p: &Panel, seq: &Sequence, plot: &Plot) {
    for (o, &huge) in seq.scene.objects.iter().zip(&plot.huge) {
        let material = &seq.scene.materials[o.material];
        let (fill, edge) = (tint(material, 0.22), shade(material));
        match o.shape {
            Shape::Plane { point, normal, .. } => c.mask(
                p.rect(),
                |x, y| (p.world_at(x, y) - point).dot(normal) < 0.0,
                fill,
                edge,
            ),
            Shape::Sphere { center, radius } if huge => c.mask(
                p.rect(),
                |x, y| p.world_at(x, y).distance(center) < radius,
                fill,
                edge,
            ),
            Shape::Sphere { .. } => {}
            Shape::Mesh { mesh, place, .. } => {
                // A mesh as the outline of its placed box, seen along the panel's depth axis.
                let (lo, hi) = seq.scene.mesh_bounds(mesh, &place);
                let (a, b) = (p.to_px(lo), p.to_px(hi));
                let (x0, x1) = (a.0.min(b.0), a.0.max(b.0));
                let (y0, y1) = (a.1.min(b.1), a.1.max(b.1));
                for (from, to) in [
                    ((x0, y0), (x1, y0)),
                    ((x1, y0), (x1, y1)),
                    ((x1, y1), (x0, y1)),
                    ((x0, y1), (x0, y0)),
                ] {
                    c.line(from, to, 1.5, edge);
                }
            }
        }
    }
}

/// Light lines every 1, 2 or 5 × 10^k units, the world axes a little darker, and the
/// spacing written in the corner.
pub(super) fn draw_grid(c: &mut Canvas, p: &Panel) {
    let r = p.rect();
    let (w, h) = (f64::from(p.width) / p.scale, f64::from(p.height) / p.scale);
    let step = nice_step(w.max(h) / 8.0);
    let (lo_a, lo_b) = (p.centre.0 - w / 2.0, p.centre.1 - h / 2.0);
    for k in (lo_a / step).ceil() as i64..=((lo_a + w) / step).floor() as i64 {
        let mut q = DVec3::ZERO;
        q[p.across] = k as f64 * step;
        let x = p.to_px(q).0;
        let colour = if k == 0 { AXIS } else { GRID };
        c.line((x, r.y0 as f64), (x, r.y1 as f64), 1.0, colour);
    }
    for k in (lo_b / step).ceil() as i64..=((lo_b + h) / step).floor() as i64 {
        let mut q = DVec3::ZERO;
        q[p.down] = k as f64 * step;
        let y = p.to_px(q).1;
        let colour = if k == 0 { AXIS } else { GRID };
        c.line((r.x0 as f64, y), (r.x1 as f64, y), 1.0, colour);
    }
    let label = format!("grid {}", fmt_num(step));
    let x = r.x1 - 8 - text_width(&label, 1);
    c.text(x, r.y0 + 8, &label, 1, MUTED);
}

/// Ordinary spheres as discs, far ones first so near ones cover them, labelled `[i]` as the
/// warnings name them.
pub(super) fn draw_spheres(c: &mut Canvas, p: &Panel, seq: &Sequence, plot: &Plot) {
    let mut order: Vec<(usize, DVec3, f64)> = Vec::new();
    for (i, o) in seq.scene.objects.iter().enumerate() {
        if let (Shape::Sphere { center, radius }, false) = (o.shape, plot.huge[i]) {
            order.push((i, center, radius));
        }
    }
    let (axis, toward) = (p.depth_axis(), p.toward_viewer());
    order.sort_by(|a, b| (toward * a.1[axis]).total_cmp(&(toward * b.1[axis])));
    for (i, center, radius) in order {
        let material = &seq.scene.materials[seq.scene.objects[i].material];
        let (cx, cy) = p.to_px(center);
        let r = radius * p.scale;
        let bbox = Rect::around((cx, cy), r + 2.0);
        let inside = |x: f64, y: f64| (x - cx).hypot(y - cy) < r;
        c.mask(bbox, inside, tint(material, 0.45), shade(material));
        let label = format!("[{i}]");
        // Inside the disc when it fits (large, else small type), otherwise just right of it.
        let fits = |scale: i64| 2.0 * r > (text_width(&label, scale) + 6) as f64;
        let scale = if fits(2) { 2 } else { 1 };
        let lw = text_width(&label, scale) as f64;
        let lx = if fits(scale) {
            cx - lw / 2.0
        } else {
            cx + r + 4.0
        };
        let ly = cy - 3.5 * scale as f64;
        c.text(lx.round() as i64, ly.round() as i64, &label, scale, LABEL);
    }
}

/// Faint dashed lines from each keyframe to its look-at target, and the look-at track when
/// the target moves.
pub(super) fn draw_target_links(c: &mut Canvas, p: &Panel, plot: &Plot) {
    for &(pos, look) in &plot.keys {
        c.dashed(p.to_px(pos), p.to_px(look), 6.0, TARGET_LINK);
    }
    if plot.targets.len() > 1 {
        let track = plot.samples.iter().map(|(_, pose)| p.to_px(pose.look_at));
        c.polyline(track, 1.0, TARGET);
    }
}

pub(super) fn draw_path(c: &mut Canvas, p: &Panel, plot: &Plot) {
    let pts: Vec<(f64, f64)> = plot
        .samples
        .iter()
        .map(|(_, s)| p.to_px(s.position))
        .collect();
    for i in 1..pts.len() {
        let bad = plot.bad[i - 1] || plot.bad[i];
        let (w, colour) = if bad { (4.0, BAD) } else { (2.0, PATH) };
        c.line(pts[i - 1], pts[i], w, colour);
    }
    // Dots at the frames show speed (bunched up near a stop) when they are far enough apart.
    let every = dot_stride(&pts);
    for (i, &pt) in pts.iter().enumerate().step_by(every) {
        let colour = if plot.bad[i] { BAD } else { PATH };
        c.disc(pt, 2.5, colour);
    }
}

/// Each moving object's (teal) and light's (amber) path, with dots spaced like the camera's
/// and its label (`[i]`, `L<i>`) at the end it reaches last. A path that stays on one spot
/// (a turntable, a light that only dims) is a ring there.
pub(super) fn draw_moving(c: &mut Canvas, p: &Panel, plot: &Plot) {
    for (thing, path) in &plot.moving {
        let (colour, label) = match thing {
            Thing::Object(i) => (OBJECT_PATH, format!("[{i}]")),
            Thing::Light(i) => (LIGHT_PATH, format!("L{i}")),
        };
        let pts: Vec<(f64, f64)> = path.iter().map(|&x| p.to_px(x)).collect();
        c.polyline(pts.iter().copied(), 1.5, colour);
        for &pt in pts.iter().step_by(dot_stride(&pts)) {
            c.disc(pt, 1.8, colour);
        }
        let end = pts[pts.len() - 1];
        if pts.iter().all(|&q| dist(q, end) < 3.0) {
            c.ring(end, 6.0, 1.5, colour);
        }
        if edge_point(p, end).is_none() {
            c.text(
                (end.0 + 7.0) as i64,
                (end.1 + 4.0) as i64,
                &label,
                1,
                colour,
            );
        }
    }
}

/// Every how many samples a dot goes, so that dots are about 5 px apart or more.
pub(super) fn dot_stride(pts: &[(f64, f64)]) -> usize {
    let mut steps: Vec<f64> = pts.windows(2).map(|w| dist(w[0], w[1])).collect();
    if steps.is_empty() {
        return 1;
    }
    steps.sort_by(f64::total_cmp);
    let median = steps[steps.len() / 2].max(1e-3);
    ((5.0 / median).ceil() as usize).clamp(1, pts.len())
}

/// Short arrows from the camera along its view direction, as long as the direction lies in
/// the panel's plane (a camera looking straight at the viewer gets a dot-sized arrow).
pub(super) fn draw_ticks(c: &mut Canvas, p: &Panel, plot: &Plot) {
    pub(super) const LENGTH: f64 = 30.0;
    for k in evenly_spaced(plot.samples.len() as u64, TICKS) {
        let pose = plot.samples[k as usize].1;
        let Ok(cam) = Camera::new(&pose) else {
            continue;
        };
        let from = p.to_px(pose.position);
        let ahead = p.to_px(pose.position + cam.forward / p.scale);
        let d = (ahead.0 - from.0, ahead.1 - from.1);
        if d.0.hypot(d.1) * LENGTH < 4.0 {
            continue;
        }
        let to = (from.0 + LENGTH * d.0, from.1 + LENGTH * d.1);
        c.arrow(from, to, 2.0, TICK);
    }
}

pub(super) fn draw_keys(c: &mut Canvas, p: &Panel, plot: &Plot) {
    for (i, &(k, _)) in plot.keys.iter().enumerate() {
        let at = p.to_px(k);
        c.square_outline(at, 8.0, 2.0, KEYFRAME);
        let label = i.to_string();
        let (x, y) = ((at.0 + 10.0) as i64, (at.1 - 22.0) as i64);
        c.text(x, y, &label, 2, KEYFRAME);
    }
}

pub(super) fn draw_targets(c: &mut Canvas, p: &Panel, plot: &Plot) {
    for &t in &plot.targets {
        match edge_point(p, p.to_px(t)) {
            None => c.cross(p.to_px(t), 6.0, 2.0, TARGET),
            Some(at) => {
                c.cross(at, 6.0, 2.0, TARGET);
                c.text_near(p, at, &format!("look-at {}", fmt_vec(t)), TARGET);
            }
        }
    }
}

pub(super) fn draw_ends(c: &mut Canvas, p: &Panel, plot: &Plot) {
    let first = p.to_px(plot.samples[0].1.position);
    let last = p.to_px(plot.samples[plot.samples.len() - 1].1.position);
    c.square(last, 6.0, END);
    c.disc(first, 7.0, PANEL);
    c.disc(first, 5.5, START);
}

/// Point and spot lights as diamonds labelled `L<i>`; one outside the view sits hollow at
/// the panel edge in its direction, with its coordinates.
pub(super) fn draw_lights(c: &mut Canvas, p: &Panel, seq: &Sequence) {
    for (i, pos) in positioned_lights(seq) {
        let at = p.to_px(pos);
        match edge_point(p, at) {
            None => {
                c.diamond(at, 8.0, LIGHT, INK);
                c.text(
                    (at.0 + 10.0) as i64,
                    (at.1 - 4.0) as i64,
                    &format!("L{i}"),
                    1,
                    INK,
                );
            }
            Some(edge) => {
                c.diamond(edge, 8.0, PANEL, INK);
                c.diamond(edge, 5.0, LIGHT, LIGHT);
                c.text_near(p, edge, &format!("L{i} {}", fmt_vec(pos)), INK);
            }
        }
    }
}

/// Where a point outside the panel is drawn: on the line from the panel's centre towards it,
/// just inside the border. None when it is inside.
pub(super) fn edge_point(p: &Panel, at: (f64, f64)) -> Option<(f64, f64)> {
    pub(super) const INSET: f64 = 12.0;
    let (cx, cy) = p.centre_px();
    let (dx, dy) = (at.0 - cx, at.1 - cy);
    let (hw, hh) = (
        f64::from(p.width) / 2.0 - INSET,
        f64::from(p.height) / 2.0 - INSET,
    );
    let t = (hw / dx.abs()).min(hh / dy.abs());
    if t.is_nan() || t >= 1.0 {
        return None;
    }
    Some((cx + t * dx, cy + t * dy))
}

/// Two small arrows in a corner naming the axes, so each panel reads without the caption.
pub(super) fn draw_gizmo(c: &mut Canvas, p: &Panel) {
    pub(super) const NAMES: [&str; 3] = ["x", "y", "z"];
    let r = p.rect();
    // The vertical arrow points into the panel: down from the top-left for the top view's z,
    // up from the bottom-left for the side view's y.
    let (ox, oy, dy) = if p.flipped {
        (r.x0 as f64 + 16.0, r.y0 as f64 + 16.0, 1.0)
    } else {
        (r.x0 as f64 + 16.0, r.y1 as f64 - 16.0, -1.0)
    };
    c.arrow((ox, oy), (ox + 34.0, oy), 1.0, MUTED);
    c.arrow((ox, oy), (ox, oy + dy * 34.0), 1.0, MUTED);
    c.text(
        (ox + 38.0) as i64,
        (oy - 3.0) as i64,
        NAMES[p.across],
        1,
        MUTED,
    );
    let ty = if dy > 0.0 { oy + 38.0 } else { oy - 45.0 };
    c.text((ox - 2.0) as i64, ty as i64, NAMES[p.down], 1, MUTED);
}
