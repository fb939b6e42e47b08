//! Rigid contact of a wheelset on a straight track, one contact point per wheel, for a given
//! lateral displacement of the wheelset: the wheelset's roll and height such that both wheels
//! touch their rails without penetration, and where they touch.
//!
//! Frames (m, rad): the track frame has y lateral (positive to the left) and z up, the top of the
//! rails at z = 0. The wheelset frame moves with the wheelset: its lateral axis ξ runs along the
//! axle from the wheelset's centre; its roll φ > 0 lifts the left wheel. The left wheel's
//! nominal rolling circle lies at ξ = d = flange-back spacing / 2 + rolling-circle offset, its
//! radius there is r0, and the wheel profile z(s) (s = ξ − d) adds to the radius: r(s) = r0 +
//! z(s). The right wheel and rail are the mirror images (ξ → −ξ, y → −y).
//!
//! The left rail is its profile turned by the inclination β (its top faces the track centre) and
//! placed so that its gauge point (its innermost point within `gauge_depth` below its top) lies
//! at y = gauge / 2 and its top at z = 0.
//!
//! For a lateral displacement y_w and a roll φ the vertical gap between the left wheel and its
//! rail, with the axle at height 0, is D_L(y_w, φ) = min over s of [z_P(s) − Z(y_P(s))], where
//! P(s) is the wheel's point at s turned by φ and Z the rail's height. The right wheel's gap is
//! D_L(−y_w, −φ). Both wheels touch when D_L(y_w, φ) = D_L(−y_w, −φ); the axle then lies at height
//! −D_L. The contact jumps (to the flange) where another local minimum of the gap becomes the
//! lowest.

use super::compute::{ContactError, ContactSettings};
use super::profile::Profile;
use crate::contact::Portable;

/// Grid spacing of the tabulated profiles (m).
const STEP: f64 = 2e-5;
/// The search for the lowest point of the gap samples every this many wheel nodes (0.5 mm).
const SCAN_NODES: usize = 25;
/// Local minima of the sampled gap this close to the lowest (m) are refined: more than the
/// sampling can miss (G''·h²/8 with G'' up to ~4000/m on the flange, h = 0.5 mm).
const CANDIDATE_MARGIN: f64 = 5e-4;
/// A roll this far from the one the candidates were found at calls for a new search (rad).
const RESCAN_ROLL: f64 = 1e-4;
/// The rail is kept where its slope in the track frame is at most this (tan 80.5°); beyond, its
/// surface is taken to drop at [`DROP`] (no wheel profile is steeper than ~70° where it can
/// touch).
const SLOPE_CAP: f64 = 6.0;
/// Slope of the rail's surface beyond the kept range.
const DROP: f64 = 50.0;
/// Largest roll accepted (rad).
const MAX_ROLL: f64 = 0.2;

/// A function on a uniform grid: values, slopes and second derivatives at the nodes; cubic
/// Hermite between nodes for value and slope, linear for the second derivative.
#[derive(Clone, Debug)]
struct Grid {
    x0: f64,
    h: f64,
    inv_h: f64,
    v: Vec<f64>,
    d: Vec<f64>,
    d2: Vec<f64>,
}

impl Grid {
    fn build(x0: f64, x1: f64, f: impl FnMut(f64) -> (f64, f64, f64)) -> Grid {
        let n = (((x1 - x0) / STEP).ceil() as usize).max(1) + 1;
        let h = (x1 - x0) / (n - 1) as f64;
        let (mut v, mut d, mut d2) = (vec![0.0; n], vec![0.0; n], vec![0.0; n]);
        let mut f = f;
        for i in 0..n {
            let x = if i + 1 == n { x1 } else { x0 + h * i as f64 };
            (v[i], d[i], d2[i]) = f(x);
        }
        Grid {
            x0,
            h,
            inv_h: 1.0 / h,
            v,
            d,
            d2,
        }
    }

    fn end(&self) -> f64 {
        self.x0 + self.h * (self.v.len() - 1) as f64
    }

    /// The cell of x and the position in it.
    #[inline]
    fn cell(&self, x: f64) -> (usize, f64) {
        let t = ((x - self.x0) * self.inv_h).max(0.0);
        let i = (t as usize).min(self.v.len() - 2);
        (i, t - i as f64)
    }

    /// The value at x ∈ [x0, end].
    #[inline]
    fn value(&self, x: f64) -> f64 {
        let (i, t) = self.cell(x);
        let (v0, v1) = (self.v[i], self.v[i + 1]);
        let (m0, m1) = (self.d[i] * self.h, self.d[i + 1] * self.h);
        v0 + t * (m0 + t * (3.0 * (v1 - v0) - 2.0 * m0 - m1 + t * (2.0 * (v0 - v1) + m0 + m1)))
    }

    /// Value, slope and second derivative at x ∈ [x0, end].
    #[inline]
    fn eval(&self, x: f64) -> (f64, f64, f64) {
        let (i, t) = self.cell(x);
        let (v0, v1) = (self.v[i], self.v[i + 1]);
        let (m0, m1) = (self.d[i] * self.h, self.d[i + 1] * self.h);
        let (t2, t3) = (t * t, t * t * t);
        let v = (2.0 * t3 - 3.0 * t2 + 1.0) * v0
            + (t3 - 2.0 * t2 + t) * m0
            + (3.0 * t2 - 2.0 * t3) * v1
            + (t3 - t2) * m1;
        let dv = ((6.0 * t2 - 6.0 * t) * (v0 - v1)
            + (3.0 * t2 - 4.0 * t + 1.0) * m0
            + (3.0 * t2 - 2.0 * t) * m1)
            / self.h;
        let d2 = (1.0 - t) * self.d2[i] + t * self.d2[i + 1];
        (v, dv, d2)
    }
}

/// The contact of one wheel.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct WheelContact {
    /// Position on the wheel profile from the nominal rolling circle, positive toward the field
    /// side (m).
    pub s: f64,
    /// Lateral position of the contact point on the wheel from the wheelset centre, along the
    /// axle (m).
    pub aw: f64,
    /// Rolling radius (m).
    pub r: f64,
    /// Contact angle relative to the axle (rad), positive when the wheel's radius grows toward
    /// the flange (the track-frame angle is δ + φ on the left wheel, δ − φ on the right).
    pub delta: f64,
    /// Lateral curvature of the wheel profile at the contact, positive convex (1/m).
    pub wheel_curvature: f64,
    /// Lateral position of the contact point in the track frame, positive outward from the
    /// track centre (m).
    pub y_track: f64,
    /// Lateral position of the contact point on the rail profile, from the rail's centre line,
    /// positive toward the field side (m).
    pub rail_u: f64,
    /// Height of the contact point below the top of the rail (≤ 0) (m).
    pub zc: f64,
    /// Lateral curvature of the rail profile at the contact, positive convex (1/m).
    pub rail_curvature: f64,
    /// Contact angle in the track frame from the rail's slope at the contact (rad): δ + φ on
    /// the left wheel, δ − φ on the right when the surfaces are tangent.
    pub rail_angle: f64,
}

/// The rigid contact of a wheelset at one lateral displacement.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct GeometryRow {
    /// Wheelset lateral displacement (m).
    pub y: f64,
    /// Wheelset roll (rad), positive lifting the left wheel.
    pub roll: f64,
    /// Height of the wheelset centre above the top of the rails (m).
    pub height: f64,
    /// Left wheel.
    pub left: WheelContact,
    /// Right wheel (mirrored: its `delta`, `aw`, `y_track` as for the left wheel in a mirror).
    pub right: WheelContact,
}

/// The lowest point of one wheel's gap at a given displacement and roll.
#[derive(Clone, Copy, Debug)]
struct Touch {
    /// The gap (axle at height 0) (m).
    gap: f64,
    /// Its derivative with respect to the roll (m/rad).
    dgap: f64,
    s: f64,
    y: f64,
}

/// A local minimum of the sampled gap: the sample s and its neighbours a < s < b (m).
#[derive(Clone, Copy, Debug)]
struct Candidate {
    a: f64,
    b: f64,
    s: f64,
}

/// The candidates of one wheel and the roll they were found at.
#[derive(Clone, Debug)]
struct Search {
    candidates: Vec<Candidate>,
    roll: f64,
}

impl Default for Search {
    fn default() -> Self {
        Search {
            candidates: Vec::new(),
            roll: f64::NAN,
        }
    }
}

/// The tabulated wheel and rail of a wheelset on a track.
#[derive(Clone, Debug)]
pub struct Geometry {
    /// Wheel radius r(s) (m).
    wheel: Grid,
    /// Left rail height Z(y) in the track frame (m).
    rail: Grid,
    /// The rail's own coordinate u at the nodes of `rail`.
    rail_u: Vec<f64>,
    /// Lateral position of the nominal rolling circle from the wheelset centre (m).
    d: f64,
}

/// The rail turned by β and placed: its height z(y) in the track frame on the kept range, and u.
fn place_rail(rail: &Profile, s: &ContactSettings) -> Result<(Grid, Vec<f64>), ContactError> {
    let (sb, cb) = s.inclination.sin_cos();
    let (ua, ub) = rail.domain();
    // Turned profile: Y(u), Z(u) and derivatives.
    let turned = |u: f64| {
        let p = rail.eval(u);
        let y = u * cb - p.z * sb;
        let z = u * sb + p.z * cb;
        let dy = cb - p.dz * sb;
        let dz = sb + p.dz * cb;
        (y, z, dy, dz, p.d2z)
    };
    // Top of the rail: the highest turned point (scan, then bisection on dZ/du = 0).
    let n = ((ub - ua) / 1e-5).ceil() as usize + 1;
    let at = |i: usize| ua + (ub - ua) * i as f64 / (n - 1) as f64;
    let itop = (0..n)
        .max_by(|&i, &j| turned(at(i)).1.total_cmp(&turned(at(j)).1))
        .unwrap_or(0);
    let (mut lo, mut hi) = (at(itop.saturating_sub(1)), at((itop + 1).min(n - 1)));
    for _ in 0..100 {
        let mid = 0.5 * (lo + hi);
        if turned(mid).3 > 0.0 {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    let u_top = 0.5 * (lo + hi);
    let z_top = turned(u_top).1;
    // Gauge point: on the gauge side (u < u_top), the innermost point at most gauge_depth below
    // the top.
    let z_gauge = z_top - s.gauge_depth;
    if turned(ua).1 > z_gauge {
        return Err(ContactError::Rail(format!(
            "the rail profile does not reach {} mm below its top on the gauge side",
            s.gauge_depth * 1e3
        )));
    }
    let (mut lo, mut hi) = (ua, u_top);
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if turned(mid).1 < z_gauge {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    let u_depth = hi;
    let m = ((u_top - u_depth) / 1e-6).ceil() as usize + 1;
    let y_gauge = (0..m)
        .map(|i| turned(u_depth + (u_top - u_depth) * i as f64 / (m - 1) as f64).0)
        .fold(turned(u_depth).0, f64::min);
    let y_off = 0.5 * s.gauge - y_gauge;
    // Kept range: around the top while the turned profile is a function of y with a slope of
    // at most SLOPE_CAP.
    let ok = |u: f64| {
        let (_, _, dy, dz, _) = turned(u);
        dy > 0.0 && dz.abs() <= SLOPE_CAP * dy
    };
    let edge = |from: f64, to: f64| {
        // Walk from `from` toward `to` while ok, then bisect the edge.
        let k = ((to - from).abs() / 1e-5).ceil() as usize;
        let mut last = from;
        for i in 1..=k {
            let u = from + (to - from) * i as f64 / k as f64;
            if !ok(u) {
                let (mut a, mut b) = (last, u);
                for _ in 0..60 {
                    let mid = 0.5 * (a + b);
                    if ok(mid) {
                        a = mid;
                    } else {
                        b = mid;
                    }
                }
                return a;
            }
            last = u;
        }
        to
    };
    let (u_lo, u_hi) = (edge(u_top, ua), edge(u_top, ub));
    let (y_lo, y_hi) = (turned(u_lo).0, turned(u_hi).0);
    let mut us = Vec::new();
    let mut guess = u_lo;
    let grid = Grid::build(y_lo + y_off, y_hi + y_off, |y| {
        // Invert Y(u) = y − y_off on [u_lo, u_hi] (Y increasing): Newton, bisection fallback.
        let target = y - y_off;
        let (mut a, mut b) = (u_lo, u_hi);
        let mut u = guess.clamp(a, b);
        for _ in 0..100 {
            let (yu, _, dy, _, _) = turned(u);
            let f = yu - target;
            if f < 0.0 {
                a = u;
            } else {
                b = u;
            }
            let mut next = u - f / dy;
            if !(next > a && next < b) {
                next = 0.5 * (a + b);
            }
            if (next - u).abs() < 1e-16 || b - a < 1e-16 {
                u = next;
                break;
            }
            u = next;
        }
        guess = u;
        us.push(u);
        let (_, z, dy, dz, d2z) = turned(u);
        (z - z_top, dz / dy, d2z / (dy * dy * dy))
    });
    Ok((grid, us))
}

impl Geometry {
    /// The wheelset and track of `settings` with the given profiles.
    pub fn new(
        wheel: &Profile,
        rail: &Profile,
        settings: &ContactSettings,
    ) -> Result<Geometry, ContactError> {
        let (s0, s1) = wheel.domain();
        let r0 = settings.r0;
        let wheel = Grid::build(s0, s1, |s| {
            let p = wheel.eval(s);
            (r0 + p.z, p.dz, p.d2z)
        });
        if wheel.v.iter().any(|&r| r <= 0.0) {
            return Err(ContactError::Settings(
                "the wheel's radius must stay positive over its profile".into(),
            ));
        }
        let (rail, rail_u) = place_rail(rail, settings)?;
        Ok(Geometry {
            wheel,
            rail,
            rail_u,
            d: 0.5 * settings.flange_back + settings.rolling_circle,
        })
    }

    /// The left rail's height, slope and second derivative at track y; beyond the kept range
    /// the surface drops away at slope [`DROP`].
    #[inline]
    fn rail_at(&self, y: f64) -> (f64, f64, f64) {
        let (a, b) = (self.rail.x0, self.rail.end());
        if y < a {
            (self.rail.v[0] - DROP * (a - y), DROP, 0.0)
        } else if y > b {
            (
                self.rail.v[self.rail.v.len() - 1] - DROP * (y - b),
                -DROP,
                0.0,
            )
        } else {
            self.rail.eval(y)
        }
    }

    /// The left rail's height at track y (as [`Geometry::rail_at`]).
    #[inline]
    fn rail_height(&self, y: f64) -> f64 {
        let (a, b) = (self.rail.x0, self.rail.end());
        if y < a {
            self.rail.v[0] - DROP * (a - y)
        } else if y > b {
            self.rail.v[self.rail.v.len() - 1] - DROP * (y - b)
        } else {
            self.rail.value(y)
        }
    }

    /// Gap at s and its first two derivatives in s; also y_P and z_P.
    #[inline]
    fn gap(&self, yw: f64, (sn, c): (f64, f64), s: f64) -> (f64, f64, f64, f64, f64) {
        let (r, dr, d2r) = self.wheel.eval(s);
        let xi = self.d + s;
        let y = yw + xi * c + r * sn;
        let z = xi * sn - r * c;
        let (zr, dzr, d2zr) = self.rail_at(y);
        let dy = c + dr * sn;
        let g = z - zr;
        let dg = (sn - dr * c) - dzr * dy;
        let d2g = -d2r * c - d2zr * dy * dy - dzr * d2r * sn;
        (g, dg, d2g, y, z)
    }

    /// The local minima of the left wheel's gap at displacement `yw` and roll `phi`, sampled
    /// every [`SCAN_NODES`] wheel nodes where the wheel lies above the rail, that come within
    /// [`CANDIDATE_MARGIN`] of the lowest sample.
    fn scan(&self, yw: f64, phi: f64, out: &mut Vec<Candidate>) {
        out.clear();
        let (sn, c) = phi.sin_cos();
        let w = &self.wheel;
        let last = w.v.len() - 1;
        // Wheel nodes above the rail's kept range (3 mm margin for the roll).
        let r0 = w.v[last / 2];
        let node = |s: f64| ((s - w.x0) * w.inv_h).clamp(0.0, last as f64);
        let from = node((self.rail.x0 - 3e-3 - yw - r0 * sn) / c - self.d).floor() as usize;
        let to = node((self.rail.end() + 3e-3 - yw - r0 * sn) / c - self.d).ceil() as usize;
        let (from, to) = if from + SCAN_NODES < to {
            (from, to)
        } else {
            (0, last)
        };
        let count = (to - from).div_ceil(SCAN_NODES) + 1;
        let at = |k: usize| (from + k * SCAN_NODES).min(to);
        let mut g = Vec::with_capacity(count);
        for k in 0..count {
            let i = at(k);
            let s = w.x0 + w.h * i as f64;
            let (xi, r) = (self.d + s, w.v[i]);
            g.push(xi * sn - r * c - self.rail_height(yw + xi * c + r * sn));
        }
        let lowest = g.iter().copied().fold(f64::INFINITY, f64::min);
        let s_of = |k: usize| w.x0 + w.h * at(k) as f64;
        for k in 0..count {
            let left_ok = k == 0 || g[k] <= g[k - 1];
            let right_ok = k + 1 == count || g[k] <= g[k + 1];
            if left_ok && right_ok && g[k] <= lowest + CANDIDATE_MARGIN {
                out.push(Candidate {
                    a: s_of(k.saturating_sub(1)),
                    b: s_of((k + 1).min(count - 1)),
                    s: s_of(k),
                });
            }
        }
    }

    /// The lowest of the candidates' refined minima, or None if one of them left its bracket
    /// (`strict`: the candidates were found at another roll and must be searched again).
    fn best(&self, yw: f64, phi: f64, cands: &mut [Candidate], strict: bool) -> Option<Touch> {
        let sc = phi.sin_cos();
        let (lo, hi) = (self.wheel.x0, self.wheel.end());
        let mut best: Option<(f64, f64)> = None;
        for cand in cands.iter_mut() {
            let (s, g) = self.refine(yw, sc, cand.a, cand.b, cand.s);
            let at_end = (s == cand.a && s > lo) || (s == cand.b && s < hi);
            if strict && at_end {
                return None;
            }
            cand.s = s;
            if best.is_none_or(|(_, gb)| g < gb) {
                best = Some((s, g));
            }
        }
        let (s, gap) = best?;
        let (_, _, _, y, z) = self.gap(yw, sc, s);
        let dzr = self.rail_at(y).1;
        Some(Touch {
            gap,
            dgap: (y - yw) + dzr * z,
            s,
            y,
        })
    }

    /// The lowest point of the left wheel's gap at displacement `yw` and roll `phi`, from the
    /// candidates in `search` (found again when the roll has moved or a candidate has left its
    /// bracket).
    fn touch(&self, yw: f64, phi: f64, search: &mut Search) -> Touch {
        if search.roll.is_nan() || (phi - search.roll).abs() > RESCAN_ROLL {
            self.scan(yw, phi, &mut search.candidates);
            search.roll = phi;
            if let Some(t) = self.best(yw, phi, &mut search.candidates, false) {
                return t;
            }
        } else if let Some(t) = self.best(yw, phi, &mut search.candidates, true) {
            return t;
        }
        self.scan(yw, phi, &mut search.candidates);
        search.roll = phi;
        self.best(yw, phi, &mut search.candidates, false)
            .unwrap_or_else(|| {
                let s = self.wheel.x0;
                let sc = phi.sin_cos();
                let (gap, _, _, y, z) = self.gap(yw, sc, s);
                Touch {
                    gap,
                    dgap: (y - yw) + self.rail_at(y).1 * z,
                    s,
                    y,
                }
            })
    }

    /// The minimum of the gap on [a, b] starting at s0: Newton on the gap's slope, kept in a
    /// bracket that shrinks around the root of the slope (bisection when Newton leaves it). An
    /// end of [a, b] when the slope does not change sign from − to + in it.
    fn refine(&self, yw: f64, sc: (f64, f64), a: f64, b: f64, s0: f64) -> (f64, f64) {
        let (mut a, mut b) = (a, b);
        let (ga, da, _, _, _) = self.gap(yw, sc, a);
        let (gb, db, _, _, _) = self.gap(yw, sc, b);
        if !(da < 0.0 && db > 0.0) {
            return if ga <= gb { (a, ga) } else { (b, gb) };
        }
        let mut s = s0.clamp(a, b);
        for _ in 0..100 {
            let (_, d, d2, _, _) = self.gap(yw, sc, s);
            if d < 0.0 {
                a = s;
            } else {
                b = s;
            }
            let mut next = s - d / d2;
            if !(d2 > 0.0 && next > a && next < b) {
                next = 0.5 * (a + b);
            }
            let done = (next - s).abs() < 1e-14 || b - a < 1e-14;
            s = next;
            if done {
                break;
            }
        }
        (s, self.gap(yw, sc, s).0)
    }

    /// The wheel's contact data at `t` (in the left wheel's frame).
    fn contact(&self, t: &Touch) -> WheelContact {
        let (r, dr, d2r) = self.wheel.eval(t.s);
        let (zr, dzr, d2zr) = self.rail_at(t.y);
        let k = ((t.y - self.rail.x0) / self.rail.h).clamp(0.0, (self.rail_u.len() - 1) as f64);
        let i = (k.floor() as usize).min(self.rail_u.len() - 2);
        let f = k - i as f64;
        WheelContact {
            s: t.s,
            aw: self.d + t.s,
            r,
            delta: (-dr).p_atan(),
            wheel_curvature: -d2r / (1.0 + dr * dr).p_powf(1.5),
            y_track: t.y,
            rail_u: (1.0 - f) * self.rail_u[i] + f * self.rail_u[i + 1],
            zc: zr,
            rail_curvature: -d2zr / (1.0 + dzr * dzr).p_powf(1.5),
            rail_angle: dzr.p_atan(),
        }
    }

    /// The rigid contact at lateral displacement `y` (m), starting the search for the roll at
    /// `roll_guess` (rad).
    pub fn solve(&self, y: f64, roll_guess: f64) -> Result<GeometryRow, ContactError> {
        let (mut lo, mut hi) = (f64::NEG_INFINITY, f64::INFINITY);
        let mut phi = roll_guess;
        let mut expand = 1e-3;
        let (mut left, mut right) = (Search::default(), Search::default());
        for _ in 0..200 {
            let l = self.touch(y, phi, &mut left);
            let r = self.touch(-y, -phi, &mut right);
            let f = l.gap - r.gap;
            let fp = l.dgap + r.dgap;
            if f.abs() <= 1e-13 || hi - lo <= 1e-15 {
                return Ok(GeometryRow {
                    y,
                    roll: phi,
                    height: -0.5 * (l.gap + r.gap),
                    left: self.contact(&l),
                    right: self.contact(&r),
                });
            }
            if f > 0.0 {
                hi = phi;
            } else {
                lo = phi;
            }
            let mut next = phi - f / fp;
            if !(fp > 0.0 && next > lo && next < hi) {
                next = if lo.is_finite() && hi.is_finite() {
                    0.5 * (lo + hi)
                } else {
                    expand *= 2.0;
                    if f > 0.0 {
                        phi - expand
                    } else {
                        phi + expand
                    }
                };
            }
            if next.abs() > MAX_ROLL {
                break;
            }
            phi = next;
        }
        Err(ContactError::NoContact { y })
    }

    /// The rigid contact at each displacement of `ys` (ascending), by continuation from the one
    /// nearest 0.
    pub fn sweep(&self, ys: &[f64]) -> Result<Vec<GeometryRow>, ContactError> {
        let mut rows = vec![GeometryRow::default(); ys.len()];
        if ys.is_empty() {
            return Ok(rows);
        }
        let i0 = (0..ys.len())
            .min_by(|&i, &j| ys[i].abs().total_cmp(&ys[j].abs()))
            .unwrap_or(0);
        rows[i0] = self.solve(ys[i0], 0.0)?;
        // Continuation outward from i0, the roll extrapolated linearly from the last two rows.
        for dir in [1isize, -1] {
            let mut i = i0 as isize + dir;
            while i >= 0 && (i as usize) < ys.len() {
                let j = (i - dir) as usize;
                let k = i - 2 * dir;
                let guess = if (k - i0 as isize) * dir >= 0 {
                    let k = k as usize;
                    let slope = (rows[j].roll - rows[k].roll) / (ys[j] - ys[k]);
                    rows[j].roll + slope * (ys[i as usize] - ys[j])
                } else {
                    rows[j].roll
                };
                rows[i as usize] = self.solve(ys[i as usize], guess)?;
                i += dir;
            }
        }
        Ok(rows)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Conical wheels (cone angle γ, radius r0 on the rolling circle at d from the centre) on
    /// rails whose heads are circles of radius ρ centred at (±e, −ρ): the contact of a cone
    /// with a circle is that of the cone offset by ρ (radius r0 + ρ√(1 + γ²) at d) with a knife
    /// edge at the circle's centre, so Δr = 2e sin φ and y = (e/γ) sin φ cos φ − (r0 + ρ√(1+γ²)
    /// − γ(e cos φ − d)) sin φ exactly. To first order in φ, Δr = 2γy / (1 − γ(r0 + ρ)/e): the
    /// textbook Δr = 2γy, which neglects the roll.
    #[test]
    fn conical_wheels_on_round_and_knife_edge_rails_follow_the_closed_form() {
        for (gamma, rho) in [(0.05, 5e-4), (0.025, 2e-3), (0.2, 5e-4)] {
            let csv: String = (0..=16)
                .map(|i| {
                    let y = 30.0 + 5.0 * i as f64;
                    format!("{y},{}\n", -gamma * (y - 70.0))
                })
                .collect();
            let wheel = Profile::wheel_from_csv(&csv, 0.07).unwrap();
            let rail = Profile::crown(rho, rho * 60f64.to_radians().p_sin()).unwrap();
            let (fb, r0) = (1.36, 0.425);
            let d = 0.5 * fb + 0.07;
            let settings = ContactSettings {
                wheel: wheel.clone(),
                rail: rail.clone(),
                inclination: 0.0,
                gauge: 2.0 * d - rho,
                gauge_depth: rho * (1.0 - 30f64.to_radians().p_cos()),
                flange_back: fb,
                rolling_circle: 0.07,
                r0,
                y_min: -0.01,
                y_max: 0.01,
                y_step: 5e-4,
                ..ContactSettings::default()
            };
            let e = 0.5 * settings.gauge + 0.5 * rho;
            let r_off = r0 + rho * (1.0 + gamma * gamma).sqrt();
            let g = Geometry::new(&wheel, &rail, &settings).unwrap();
            let rows = g.sweep(&settings.displacements().unwrap()).unwrap();
            for row in &rows {
                let (sn, c) = row.roll.sin_cos();
                let dr = row.left.r - row.right.r;
                let y = e / gamma * sn * c - (r_off - gamma * (e * c - d)) * sn;
                assert!(
                    (dr - 2.0 * e * sn).abs() < 2e-9,
                    "γ {gamma}: Δr {dr} at {}",
                    row.y
                );
                assert!((row.y - y).abs() < 2e-9, "γ {gamma}: y {} vs {y}", row.y);
                if row.y.abs() > 1e-6 {
                    let first = 1.0 / (1.0 - gamma * (r0 + rho) / e);
                    let ratio = dr / (2.0 * gamma * row.y);
                    assert!((ratio / first - 1.0).abs() < 2e-3, "{ratio} vs {first}");
                }
            }
        }
    }

    #[test]
    fn contact_points_are_points_of_common_tangency() {
        let settings = ContactSettings {
            y_step: 1e-4,
            ..ContactSettings::default()
        };
        let g = Geometry::new(&settings.wheel, &settings.rail, &settings).unwrap();
        for row in g.sweep(&settings.displacements().unwrap()).unwrap() {
            let (l, r) = (&row.left, &row.right);
            assert!(
                (l.rail_angle - (l.delta + row.roll)).abs() < 1e-6,
                "{row:?}"
            );
            assert!(
                (r.rail_angle - (r.delta - row.roll)).abs() < 1e-6,
                "{row:?}"
            );
            // Both wheels on their rails: the same height of the axle over each.
            assert!(l.zc <= 0.0 && r.zc <= 0.0);
        }
    }
}
