//! `model.png`: the picture an FMI tool shows for an FMU, drawn here for each model (no image
//! file is checked in). A small anti-aliased rasterizer: shapes in the unit square (x right,
//! y down), each pixel sampled 4 x 4 times, painted in order with the "over" operator.

/// Width and height of the icon [px].
pub const SIZE: usize = 256;
/// Samples per pixel edge (16 samples per pixel).
const SS: usize = 4;

type Rgb = [u8; 3];
type Pt = (f64, f64);

const BACKGROUND: Rgb = [236, 241, 246];
const DARK: Rgb = [52, 58, 64];
const STEEL: Rgb = [132, 142, 152];
const LIGHT_STEEL: Rgb = [190, 198, 206];
const BLUE: Rgb = [43, 108, 176];
const DEEP_BLUE: Rgb = [28, 72, 122];
const ORANGE: Rgb = [221, 132, 42];
const WOOD: Rgb = [146, 110, 76];
const BALLAST: Rgb = [178, 166, 150];
const GLASS: Rgb = [214, 232, 248];

/// A filled shape in unit coordinates.
#[derive(Clone, Debug)]
enum Shape {
    /// Disc of centre `c` and radius `r`.
    Circle { c: Pt, r: f64 },
    /// Annulus between radii `r_in` and `r_out`.
    Ring { c: Pt, r_in: f64, r_out: f64 },
    /// Axis-aligned rectangle with corners rounded to radius `r` (0: sharp).
    RoundRect { min: Pt, max: Pt, r: f64 },
    /// Convex polygon (either orientation).
    Polygon(Vec<Pt>),
    /// Segment from `a` to `b` of width `w` with round ends.
    Capsule { a: Pt, b: Pt, w: f64 },
}

impl Shape {
    fn contains(&self, (x, y): Pt) -> bool {
        match self {
            Shape::Circle { c, r } => (x - c.0).hypot(y - c.1) <= *r,
            Shape::Ring { c, r_in, r_out } => {
                let d = (x - c.0).hypot(y - c.1);
                d >= *r_in && d <= *r_out
            }
            Shape::RoundRect { min, max, r } => {
                let (cx, cy) = (x.clamp(min.0 + r, max.0 - r), y.clamp(min.1 + r, max.1 - r));
                x >= min.0 && x <= max.0 && y >= min.1 && y <= max.1 && (x - cx).hypot(y - cy) <= *r
            }
            Shape::Polygon(p) => {
                let mut sign = 0.0;
                for (i, a) in p.iter().enumerate() {
                    let b = p[(i + 1) % p.len()];
                    let cross = (b.0 - a.0) * (y - a.1) - (b.1 - a.1) * (x - a.0);
                    if cross != 0.0 {
                        if sign * cross < 0.0 {
                            return false;
                        }
                        sign = cross;
                    }
                }
                true
            }
            Shape::Capsule { a, b, w } => {
                let (dx, dy) = (b.0 - a.0, b.1 - a.1);
                let len2 = dx * dx + dy * dy;
                let t = if len2 > 0.0 {
                    (((x - a.0) * dx + (y - a.1) * dy) / len2).clamp(0.0, 1.0)
                } else {
                    0.0
                };
                (x - a.0 - t * dx).hypot(y - a.1 - t * dy) <= w / 2.0
            }
        }
    }

    /// (min, max) corners of a box holding the shape.
    fn bounds(&self) -> (Pt, Pt) {
        match self {
            Shape::Circle { c, r } | Shape::Ring { c, r_out: r, .. } => {
                ((c.0 - r, c.1 - r), (c.0 + r, c.1 + r))
            }
            Shape::RoundRect { min, max, .. } => (*min, *max),
            Shape::Polygon(p) => p.iter().fold(
                ((f64::MAX, f64::MAX), (f64::MIN, f64::MIN)),
                |(lo, hi), q| {
                    (
                        (lo.0.min(q.0), lo.1.min(q.1)),
                        (hi.0.max(q.0), hi.1.max(q.1)),
                    )
                },
            ),
            Shape::Capsule { a, b, w } => (
                (a.0.min(b.0) - w / 2.0, a.1.min(b.1) - w / 2.0),
                (a.0.max(b.0) + w / 2.0, a.1.max(b.1) + w / 2.0),
            ),
        }
    }
}

fn rect(x0: f64, y0: f64, x1: f64, y1: f64) -> Shape {
    round_rect((x0, y0), (x1, y1), 0.0)
}

/// An axis-aligned rectangle from `min` to `max` with corners rounded to radius `r`.
fn round_rect(min: Pt, max: Pt, r: f64) -> Shape {
    Shape::RoundRect { min, max, r }
}

/// A segment from `a` to `b` of width `w` with round ends.
fn capsule(a: Pt, b: Pt, w: f64) -> Shape {
    Shape::Capsule { a, b, w }
}

/// The ballast bed under a side-view track.
fn ballast() -> (Shape, Rgb) {
    (
        Shape::Polygon(vec![(0.03, 0.95), (0.97, 0.95), (0.9, 0.86), (0.1, 0.86)]),
        BALLAST,
    )
}

/// A `w` x `h` rectangle centred on `c`, turned by `angle` [rad] about `pivot`.
fn turned_rect(c: Pt, w: f64, h: f64, pivot: Pt, angle: f64) -> Shape {
    let (s, co) = angle.sin_cos();
    let corners = [(-w, -h), (w, -h), (w, h), (-w, h)].map(|(dx, dy)| {
        let (px, py) = (c.0 + dx / 2.0 - pivot.0, c.1 + dy / 2.0 - pivot.1);
        (pivot.0 + co * px - s * py, pivot.1 + s * px + co * py)
    });
    Shape::Polygon(corners.to_vec())
}

/// A coil spring from `a` to `b` drawn in orange as a zigzag of `coils` turns, `width` wide.
fn spring(a: Pt, b: Pt, coils: usize, width: f64, line: f64) -> Vec<(Shape, Rgb)> {
    let (dx, dy) = (b.0 - a.0, b.1 - a.1);
    let len = dx.hypot(dy);
    let (ux, uy) = (dx / len, dy / len);
    let (nx, ny) = (-uy * width / 2.0, ux * width / 2.0);
    let lead = 0.15 * len;
    let at = |s: f64, side: f64| (a.0 + ux * s + nx * side, a.1 + uy * s + ny * side);
    let mut pts = vec![a, at(lead, 0.0)];
    let n = 2 * coils;
    for i in 0..n {
        let s = lead + (len - 2.0 * lead) * (i as f64 + 0.5) / n as f64;
        pts.push(at(s, if i % 2 == 0 { 1.0 } else { -1.0 }));
    }
    pts.extend([at(len - lead, 0.0), b]);
    pts.windows(2)
        .map(|p| (capsule(p[0], p[1], line), ORANGE))
        .collect()
}

/// A vertical viscous damper from `top` down to `bottom` (x = top.0): rod, piston, cylinder.
fn damper(top: Pt, bottom: Pt, width: f64, line: f64) -> Vec<(Shape, Rgb)> {
    let x = top.0;
    let mid = (top.1 + bottom.1) / 2.0;
    let half = width / 2.0;
    vec![
        (capsule(top, (x, mid + 0.02), line), DARK),
        (
            rect(x - half * 0.75, mid + 0.01, x + half * 0.75, mid + 0.03),
            DARK,
        ),
        (rect(x - half, mid - 0.03, x - half + line, bottom.1), STEEL),
        (rect(x + half - line, mid - 0.03, x + half, bottom.1), STEEL),
        (rect(x - half, bottom.1 - line, x + half, bottom.1), STEEL),
    ]
}

/// A side-view railway wheel of radius `r` centred on `c`.
fn wheel(c: Pt, r: f64) -> Vec<(Shape, Rgb)> {
    vec![
        (Shape::Circle { c, r: r * 1.08 }, STEEL),
        (
            Shape::Ring {
                c,
                r_in: r * 0.78,
                r_out: r,
            },
            DARK,
        ),
        (Shape::Circle { c, r: r * 0.78 }, LIGHT_STEEL),
        (Shape::Circle { c, r: r * 0.24 }, DARK),
    ]
}

/// A rail seen from the side on sleepers, from x0 to x1 with its top at `y`.
fn track(x0: f64, x1: f64, y: f64, sleepers: usize) -> Vec<(Shape, Rgb)> {
    let mut s = Vec::new();
    let pitch = (x1 - x0) / sleepers as f64;
    for i in 0..sleepers {
        let cx = x0 + pitch * (i as f64 + 0.5);
        s.push((rect(cx - 0.045, y + 0.045, cx + 0.045, y + 0.09), WOOD));
    }
    s.push((rect(x0, y, x1, y + 0.05), STEEL));
    s.push((rect(x0, y, x1, y + 0.012), LIGHT_STEEL));
    s
}

/// The single-DOF wheel: a wheel on a rail, hung from a fixed frame by a spring K and a damper C.
fn wheel_scene() -> Vec<(Shape, Rgb)> {
    let mut s = vec![(rect(0.12, 0.07, 0.88, 0.12), DARK)];
    for i in 0..8 {
        let x = 0.14 + 0.1 * i as f64;
        s.push((capsule((x, 0.07), (x + 0.04, 0.035), 0.014), DARK));
    }
    s.extend(spring((0.34, 0.12), (0.34, 0.35), 4, 0.1, 0.022));
    s.extend(damper((0.66, 0.12), (0.66, 0.35), 0.1, 0.018));
    s.push((capsule((0.5, 0.35), (0.5, 0.58), 0.035), DARK));
    s.push((round_rect((0.26, 0.335), (0.74, 0.375), 0.012), DEEP_BLUE));
    s.extend(track(0.06, 0.94, 0.8, 4));
    s.extend(wheel((0.5, 0.595), 0.19));
    s
}

/// The bogie seen from above: frame and two wheelsets on two rails, displaced laterally and
/// turned in yaw (the model's two degrees of freedom).
fn bogie_scene() -> Vec<(Shape, Rgb)> {
    let mut s = Vec::new();
    for i in 0..6 {
        let x = 0.1 + 0.16 * i as f64;
        s.push((rect(x - 0.035, 0.16, x + 0.035, 0.84), WOOD));
    }
    for y in [0.26, 0.71] {
        s.push((rect(0.04, y, 0.96, y + 0.03), STEEL));
    }
    let pivot = (0.5, 0.5);
    let yaw = 0.08;
    let part = |cx: f64, cy: f64, w: f64, h: f64| turned_rect((cx, cy), w, h, pivot, yaw);
    for x in [0.3, 0.7] {
        s.push((part(x, 0.5, 0.025, 0.5), DARK));
        for y in [0.275, 0.725] {
            s.push((part(x, y, 0.15, 0.05), DARK));
        }
    }
    for y in [0.34, 0.66] {
        s.push((part(0.5, y, 0.66, 0.06), BLUE));
    }
    s.push((part(0.5, 0.5, 0.08, 0.38), BLUE));
    s.push((Shape::Circle { c: pivot, r: 0.045 }, DEEP_BLUE));
    s
}

/// The vehicle on the track (side view): car body on two bogies, four wheels, rail on
/// sleepers and ballast.
fn vehicle_track_scene() -> Vec<(Shape, Rgb)> {
    let mut s = vec![ballast()];
    s.extend(track(0.04, 0.96, 0.77, 7));
    for bogie_x in [0.25, 0.75] {
        for dx in [-0.1, 0.1] {
            s.extend(wheel((bogie_x + dx, 0.705), 0.06));
            s.extend(spring(
                (bogie_x + dx, 0.6),
                (bogie_x + dx, 0.67),
                2,
                0.05,
                0.012,
            ));
        }
        s.push((
            round_rect((bogie_x - 0.17, 0.565), (bogie_x + 0.17, 0.605), 0.01),
            DEEP_BLUE,
        ));
        s.extend(spring((bogie_x, 0.47), (bogie_x, 0.565), 3, 0.07, 0.016));
    }
    s.push((round_rect((0.05, 0.15), (0.95, 0.48), 0.05), BLUE));
    for i in 0..5 {
        let x = 0.12 + 0.16 * i as f64;
        s.push((round_rect((x, 0.22), (x + 0.1, 0.32), 0.015), GLASS));
    }
    s.push((rect(0.05, 0.4, 0.95, 0.42), DEEP_BLUE));
    s
}

/// The full car seen from the front: car body rolled a little on the secondary springs, a bogie
/// frame on the primary springs, a wheelset with coned wheels on two rails.
fn vehicle_scene() -> Vec<(Shape, Rgb)> {
    let mut s = vec![ballast()];
    s.push((rect(0.08, 0.83, 0.92, 0.87), WOOD));
    for x in [0.2, 0.8] {
        s.push((rect(x - 0.035, 0.8, x + 0.035, 0.83), STEEL));
        s.push((rect(x - 0.02, 0.78, x + 0.02, 0.8), LIGHT_STEEL));
    }
    // Wheelset: axle and two coned wheels with their flanges inside the rails.
    s.push((capsule((0.12, 0.7), (0.88, 0.7), 0.03), DARK));
    for (x, side) in [(0.2, 1.0), (0.8, -1.0)] {
        // The tread is coned: the rolling radius grows towards the flange (inside).
        let (outer, inner) = (0.77, 0.78);
        let (left, right) = if side > 0.0 {
            (outer, inner)
        } else {
            (inner, outer)
        };
        s.push((
            Shape::Polygon(vec![
                (x - 0.05, 0.62),
                (x + 0.05, 0.62),
                (x + 0.05, right),
                (x - 0.05, left),
            ]),
            DARK,
        ));
        s.push((
            rect(x + 0.04 * side - 0.012, 0.62, x + 0.04 * side + 0.012, 0.81),
            DARK,
        ));
    }
    // Primary springs from the axle boxes to the bogie frame.
    for x in [0.1, 0.9] {
        s.push((rect(x - 0.035, 0.67, x + 0.035, 0.73), STEEL));
        s.extend(spring((x, 0.67), (x, 0.6), 2, 0.05, 0.012));
    }
    s.push((round_rect((0.05, 0.55), (0.95, 0.6), 0.012), DEEP_BLUE));
    // Secondary springs and the car body, rolled about the floor's centre.
    for x in [0.3, 0.7] {
        s.extend(spring((x, 0.55), (x, 0.46), 3, 0.07, 0.016));
    }
    let pivot = (0.5, 0.45);
    let roll = -0.03;
    s.push((turned_rect((0.5, 0.28), 0.86, 0.36, pivot, roll), BLUE));
    for x in [0.24, 0.5, 0.76] {
        s.push((turned_rect((x, 0.24), 0.16, 0.1, pivot, roll), GLASS));
    }
    s.push((
        turned_rect((0.5, 0.44), 0.86, 0.025, pivot, roll),
        DEEP_BLUE,
    ));
    s
}

/// Premultiplied RGBA pixels in 0..1.
struct Canvas {
    px: Vec<[f32; 4]>,
}

impl Canvas {
    fn new() -> Self {
        Canvas {
            px: vec![[0.0; 4]; SIZE * SIZE],
        }
    }

    /// Paints `shape` over the canvas, weighting each pixel by the share of its samples inside.
    fn fill(&mut self, shape: &Shape, color: Rgb) {
        let (lo, hi) = shape.bounds();
        let to_px = |v: f64| (v * SIZE as f64).floor().clamp(0.0, SIZE as f64) as usize;
        let (i0, i1) = (to_px(lo.0), (to_px(hi.0) + 1).min(SIZE));
        let (j0, j1) = (to_px(lo.1), (to_px(hi.1) + 1).min(SIZE));
        let rgb = color.map(|c| f32::from(c) / 255.0);
        for j in j0..j1 {
            for i in i0..i1 {
                let mut inside = 0;
                for sj in 0..SS {
                    for si in 0..SS {
                        let x = (i as f64 + (si as f64 + 0.5) / SS as f64) / SIZE as f64;
                        let y = (j as f64 + (sj as f64 + 0.5) / SS as f64) / SIZE as f64;
                        inside += usize::from(shape.contains((x, y)));
                    }
                }
                if inside == 0 {
                    continue;
                }
                let a = inside as f32 / (SS * SS) as f32;
                let p = &mut self.px[j * SIZE + i];
                for k in 0..3 {
                    p[k] = rgb[k] * a + p[k] * (1.0 - a);
                }
                p[3] = a + p[3] * (1.0 - a);
            }
        }
    }

    /// 8-bit straight-alpha RGBA rows.
    fn rgba8(&self) -> Vec<u8> {
        let q = |v: f32| (v.clamp(0.0, 1.0) * 255.0).round() as u8;
        self.px
            .iter()
            .flat_map(|p| {
                let a = p[3];
                let un = |c: f32| if a > 0.0 { q(c / a) } else { 0 };
                [un(p[0]), un(p[1]), un(p[2]), q(a)]
            })
            .collect()
    }
}

/// The icon of model `name` as PNG bytes (RGBA, [`SIZE`] x [`SIZE`]). A model without a
/// picture of its own gets the wheel on the rail.
pub fn model_png(name: &str) -> Vec<u8> {
    let scene = match name {
        "Bogie" => bogie_scene(),
        "VehicleTrack" => vehicle_track_scene(),
        "Vehicle" => vehicle_scene(),
        _ => wheel_scene(),
    };
    let mut canvas = Canvas::new();
    canvas.fill(&round_rect((0.0, 0.0), (1.0, 1.0), 0.12), BACKGROUND);
    for (shape, color) in &scene {
        canvas.fill(shape, *color);
    }
    let mut out = Vec::new();
    let mut enc = png::Encoder::new(&mut out, SIZE as u32, SIZE as u32);
    enc.set_color(png::ColorType::Rgba);
    enc.set_depth(png::BitDepth::Eight);
    let mut writer = enc
        .write_header()
        .expect("writing a PNG header to memory cannot fail");
    writer
        .write_image_data(&canvas.rgba8())
        .expect("the image has SIZE x SIZE RGBA pixels");
    writer
        .finish()
        .expect("finishing a PNG in memory cannot fail");
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::collections::HashSet;

    fn decode(bytes: &[u8]) -> (png::OutputInfo, Vec<u8>) {
        let mut reader = png::Decoder::new(bytes).read_info().unwrap();
        let mut buf = vec![0; reader.output_buffer_size()];
        let info = reader.next_frame(&mut buf).unwrap();
        buf.truncate(info.buffer_size());
        (info, buf)
    }

    #[test]
    fn each_model_gets_a_distinct_decodable_picture() {
        let mut seen = HashSet::new();
        for name in ["Wheel", "Bogie", "VehicleTrack", "Vehicle"] {
            let bytes = model_png(name);
            let (info, px) = decode(&bytes);
            assert_eq!((info.width, info.height), (SIZE as u32, SIZE as u32));
            assert_eq!(info.color_type, png::ColorType::Rgba);
            let colours: HashSet<_> = px.chunks(4).map(|p| [p[0], p[1], p[2], p[3]]).collect();
            assert!(colours.len() > 50, "{name}: {} colours", colours.len());
            // Opaque everywhere but the rounded corners (the background square).
            let transparent = px.chunks(4).filter(|p| p[3] == 0).count();
            assert!(transparent > 0 && transparent < SIZE * SIZE / 50, "{name}");
            // Not just background: the drawing covers a good part of the square.
            let drawn = px
                .chunks(4)
                .filter(|p| p[3] == 255 && p[..3] != BACKGROUND)
                .count();
            assert!(drawn > SIZE * SIZE / 5, "{name}: {drawn} drawn pixels");
            assert!(seen.insert(px), "{name} looks like another model");
        }
    }

    #[test]
    fn anti_aliased_edges_have_partial_coverage() {
        let mut c = Canvas::new();
        c.fill(
            &Shape::Circle {
                c: (0.5, 0.5),
                r: 0.3,
            },
            DARK,
        );
        let alphas: HashSet<u32> = c.px.iter().map(|p| (p[3] * 16.0).round() as u32).collect();
        assert!(alphas.len() > 8, "{alphas:?}");
        // Area of the disc, from the coverage, within 0.5 %.
        let area: f64 = c.px.iter().map(|p| f64::from(p[3])).sum::<f64>() / (SIZE * SIZE) as f64;
        let exact = std::f64::consts::PI * 0.09;
        assert!((area - exact).abs() < 0.005 * exact, "{area} vs {exact}");
    }

    #[test]
    fn convex_polygon_accepts_either_orientation() {
        let cw = Shape::Polygon(vec![(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)]);
        let ccw = Shape::Polygon(vec![(0.0, 0.0), (0.0, 1.0), (1.0, 1.0), (1.0, 0.0)]);
        for s in [cw, ccw] {
            assert!(s.contains((0.5, 0.5)));
            assert!(!s.contains((1.5, 0.5)));
            assert!(!s.contains((-0.1, 0.5)));
        }
    }
}
