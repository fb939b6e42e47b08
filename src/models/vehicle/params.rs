//! The car's parameters (SI units) and what follows from them: the bodies' nominal positions,
//! masses and inertias, and the 36 suspension elements with their attachment points.
//!
//! All attachment points are in the local frame of their body, relative to its centre of mass
//! (MODELS §5.3); an element acts along one axis of the track frame, between the two points:
//!
//! ```text
//! body          nominal centre (x, y, z)                   (z above rail level)
//! car body      (0, 0, r0 + h1 + h2)
//! bogie b       (±u1, 0, r0 + h1)                        b = 1 leading (+), 2 trailing (−)
//! wheelset w    (±u1 ± u2, 0, r0)                         w = 1 .. 4 from the front
//!
//! secondary (car body point | bogie point), per bogie and side σ = ±1 (left +):
//!   lateral  k4, D2   (±u1, σ(a+l1+l2+l3), −(h2−s2)) | (0, σ(a+l1+l2), s2)
//!   vertical k5, D1   (±u1, σ s3, −v4)               | (0, σ s3, v1+v2)
//!   yaw      k6, D6   (±(u1+s4), σ(a+l1+l2+l3/2), −h2) | (0, σ(a+l1+l2+l3/2), 0)    (x axis)
//! primary (bogie point | wheelset point), per wheelset (± = its side of the bogie) and side:
//!   lateral      k1, D5  (±u2, σ(a+l1), −h1) | (0, σ a, 0)
//!   vertical     k3, D4  (±u2, σ s1, v1)     | (0, σ s1, 0)
//!   longitudinal k2, D3  (±x1, σ s1, −h1)    | (0, σ s1, 0)                           (x axis)
//! ```
//!
//! D1, D2 and D6 act along their axis like the springs beside them; D3, D4 and D5 act along
//! the current vector between their points. The vertical springs are preloaded so that the
//! nominal position is the static equilibrium: each secondary spring carries m_c g/4 and each
//! primary spring (m_c + 2 m_b) g/8 there.
#![forbid(unsafe_code)]

/// Acceleration of gravity (m/s²), as in the reference implementation.
pub const GRAVITY: f64 = 9.81;

/// Number of bodies: car body, two bogie frames, four wheelsets.
pub const BODIES: usize = 7;
/// Index of the car body among the bodies.
pub const CAR: usize = 0;
/// Index of bogie frame `b` (0 leading, 1 trailing).
pub const fn bogie(b: usize) -> usize {
    1 + b
}
/// Index of wheelset `w` (0 = the leading wheelset of the car .. 3 = the last).
pub const fn wheelset(w: usize) -> usize {
    3 + w
}
/// Number of suspension elements (spring with its damper beside it).
pub const LINKS: usize = 36;

/// Every parameter of the car (SI units; see the variable table for each one's meaning).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Params {
    /// Car body mass (kg) and roll, pitch, yaw inertias (kg·m²).
    pub m_c: f64,
    /// Car body roll inertia (kg·m²).
    pub ix_c: f64,
    /// Car body pitch inertia (kg·m²).
    pub iy_c: f64,
    /// Car body yaw inertia (kg·m²).
    pub iz_c: f64,
    /// Bogie frame mass (kg).
    pub m_b: f64,
    /// Bogie frame roll inertia (kg·m²).
    pub ix_b: f64,
    /// Bogie frame pitch inertia (kg·m²).
    pub iy_b: f64,
    /// Bogie frame yaw inertia (kg·m²).
    pub iz_b: f64,
    /// Wheelset mass (kg).
    pub m_w: f64,
    /// Wheelset roll inertia (kg·m²).
    pub ix_w: f64,
    /// Wheelset spin inertia (kg·m²).
    pub iy_w: f64,
    /// Wheelset yaw inertia (kg·m²).
    pub iz_w: f64,
    /// Geometry (m), MODELS §5.3.
    pub r0: f64,
    /// Height of the bogie-frame centre above the axle (m).
    pub h1: f64,
    /// Height of the car-body centre of mass above the bogie-frame centre (m).
    pub h2: f64,
    /// Half lateral distance of the contact points (m).
    pub a: f64,
    /// Length of the primary lateral spring (m).
    pub l1: f64,
    /// Lateral offset of the secondary lateral spring (m).
    pub l2: f64,
    /// Length of the secondary lateral spring (m).
    pub l3: f64,
    /// Height of the primary vertical spring's bogie point (m).
    pub v1: f64,
    /// Offset of the secondary vertical spring's bogie point above v1 (m).
    pub v2: f64,
    /// Read but not used by the model (m).
    pub v3: f64,
    /// Depth of the secondary vertical spring's car-body point below its centre of mass (m).
    pub v4: f64,
    /// Half distance between the bogie centres (m).
    pub u1: f64,
    /// Half wheelbase (m).
    pub u2: f64,
    /// Longitudinal position of the primary longitudinal spring's bogie point (m).
    pub x1: f64,
    /// Lateral half spacing of the primary vertical and longitudinal springs (m).
    pub s1: f64,
    /// Height of the secondary lateral spring above the bogie centre (m).
    pub s2: f64,
    /// Lateral half spacing of the secondary vertical springs (m).
    pub s3: f64,
    /// Length of the yaw damper along x (m).
    pub s4: f64,
    /// Stiffnesses k1 .. k6 (N/m).
    pub k: [f64; 6],
    /// Dampings D1 .. D6 (N·s/m).
    pub d: [f64; 6],
    /// Friction coefficient (1).
    pub mu: f64,
    /// Shear modulus in Kalker's law (Pa).
    pub g_mod: f64,
    /// The wheelset's roll moment: 0 that of the vertical contact forces about the lever arm
    /// aw (as the reference implementation); 1 also that of the lateral contact forces about
    /// the rolling radius r.
    pub roll_moment: i32,
}

impl Params {
    /// Every parameter zero (the variable table then sets the defaults).
    pub const ZERO: Params = Params {
        m_c: 0.0,
        ix_c: 0.0,
        iy_c: 0.0,
        iz_c: 0.0,
        m_b: 0.0,
        ix_b: 0.0,
        iy_b: 0.0,
        iz_b: 0.0,
        m_w: 0.0,
        ix_w: 0.0,
        iy_w: 0.0,
        iz_w: 0.0,
        r0: 0.0,
        h1: 0.0,
        h2: 0.0,
        a: 0.0,
        l1: 0.0,
        l2: 0.0,
        l3: 0.0,
        v1: 0.0,
        v2: 0.0,
        v3: 0.0,
        v4: 0.0,
        u1: 0.0,
        u2: 0.0,
        x1: 0.0,
        s1: 0.0,
        s2: 0.0,
        s3: 0.0,
        s4: 0.0,
        k: [0.0; 6],
        d: [0.0; 6],
        mu: 0.0,
        g_mod: 0.0,
        roll_moment: 0,
    };

    /// Mass (kg) of body `i`.
    pub fn mass(&self, i: usize) -> f64 {
        match i {
            CAR => self.m_c,
            1 | 2 => self.m_b,
            _ => self.m_w,
        }
    }

    /// Roll, pitch (spin for a wheelset) and yaw inertias (kg·m²) of body `i`.
    pub fn inertia(&self, i: usize) -> [f64; 3] {
        match i {
            CAR => [self.ix_c, self.iy_c, self.iz_c],
            1 | 2 => [self.ix_b, self.iy_b, self.iz_b],
            _ => [self.ix_w, self.iy_w, self.iz_w],
        }
    }

    /// Weight of the whole car (N).
    pub fn weight(&self) -> f64 {
        (self.m_c + 2.0 * self.m_b + 4.0 * self.m_w) * GRAVITY
    }

    /// Sign of the longitudinal position of bogie `b` (+1 leading, −1 trailing).
    pub fn bogie_sign(b: usize) -> f64 {
        if b == 0 {
            1.0
        } else {
            -1.0
        }
    }

    /// Sign of wheelset `w`'s position within its bogie (+1 leading, −1 trailing).
    pub fn wheelset_sign(w: usize) -> f64 {
        if w.is_multiple_of(2) {
            1.0
        } else {
            -1.0
        }
    }

    /// Longitudinal position (m) of wheelset `w` relative to the car body centre.
    pub fn wheelset_x(&self, w: usize) -> f64 {
        Self::bogie_sign(w / 2) * self.u1 + Self::wheelset_sign(w) * self.u2
    }

    /// Nominal position (m) of the centre of body `i` in the track frame.
    pub fn centre(&self, i: usize) -> [f64; 3] {
        match i {
            CAR => [0.0, 0.0, self.r0 + self.h1 + self.h2],
            1 | 2 => [Self::bogie_sign(i - 1) * self.u1, 0.0, self.r0 + self.h1],
            _ => [self.wheelset_x(i - 3), 0.0, self.r0],
        }
    }

    /// The 36 suspension elements.
    pub fn links(&self) -> [Link; LINKS] {
        let (a, l1, l2, l3) = (self.a, self.l1, self.l2, self.l3);
        let mut out = Vec::with_capacity(LINKS);
        // Secondary suspension: car body (upper) and bogie b (lower).
        let secondary_load = self.m_c * GRAVITY / 4.0;
        for b in 0..2 {
            let sb = Self::bogie_sign(b);
            for side in [1.0, -1.0] {
                out.push(self.link(
                    "secondary lateral spring",
                    CAR,
                    bogie(b),
                    [
                        sb * self.u1,
                        side * (a + l1 + l2 + l3),
                        -(self.h2 - self.s2),
                    ],
                    [0.0, side * (a + l1 + l2), self.s2],
                    (1, self.k[3], 0.0),
                    (self.d[1], DamperKind::Axis),
                ));
                out.push(self.link(
                    "secondary vertical spring",
                    CAR,
                    bogie(b),
                    [sb * self.u1, side * self.s3, -self.v4],
                    [0.0, side * self.s3, self.v1 + self.v2],
                    (2, self.k[4], secondary_load),
                    (self.d[0], DamperKind::Axis),
                ));
                let yaw_y = side * (a + l1 + l2 + l3 / 2.0);
                out.push(self.link(
                    "yaw spring",
                    CAR,
                    bogie(b),
                    [sb * (self.u1 + self.s4), yaw_y, -self.h2],
                    [0.0, yaw_y, 0.0],
                    (0, self.k[5], 0.0),
                    (self.d[5], DamperKind::Axis),
                ));
            }
        }
        // Primary suspension: bogie (upper) and wheelset w (lower).
        let primary_load = (self.m_c + 2.0 * self.m_b) * GRAVITY / 8.0;
        for w in 0..4 {
            let sw = Self::wheelset_sign(w);
            for side in [1.0, -1.0] {
                out.push(self.link(
                    "primary lateral spring",
                    bogie(w / 2),
                    wheelset(w),
                    [sw * self.u2, side * (a + l1), -self.h1],
                    [0.0, side * a, 0.0],
                    (1, self.k[0], 0.0),
                    (self.d[4], DamperKind::Vector),
                ));
                out.push(self.link(
                    "primary vertical spring",
                    bogie(w / 2),
                    wheelset(w),
                    [sw * self.u2, side * self.s1, self.v1],
                    [0.0, side * self.s1, 0.0],
                    (2, self.k[2], primary_load),
                    (self.d[3], DamperKind::Vector),
                ));
                out.push(self.link(
                    "primary longitudinal spring",
                    bogie(w / 2),
                    wheelset(w),
                    [sw * self.x1, side * self.s1, -self.h1],
                    [0.0, side * self.s1, 0.0],
                    (0, self.k[1], 0.0),
                    (self.d[2], DamperKind::Vector),
                ));
            }
        }
        out.try_into().expect("36 links")
    }

    /// One element between `upper` (point `pu`) and `lower` (point `pl`): a spring along
    /// `axis` of stiffness `k` carrying the compressive preload `load` (N) at the nominal
    /// position, and a damper.
    #[allow(clippy::too_many_arguments)]
    fn link(
        &self,
        name: &'static str,
        upper: usize,
        lower: usize,
        pu: [f64; 3],
        pl: [f64; 3],
        (axis, k, load): (usize, f64, f64),
        (damping, damper): (f64, DamperKind),
    ) -> Link {
        let (cu, cl) = (self.centre(upper), self.centre(lower));
        let dc: [f64; 3] = std::array::from_fn(|i| cu[i] - cl[i]);
        let rest = dc[axis] + pu[axis] - pl[axis];
        // The preload as a longer rest length: at the nominal position the spring is shorter
        // than at rest by load/k, and pushes the bodies apart with `load`.
        // (k3 and k5, the preloaded springs, are > 0: the variable table refuses 0.)
        let rest_length = rest.abs() + if load > 0.0 { load / k } else { 0.0 };
        Link {
            name,
            upper,
            lower,
            pu,
            pl,
            dc,
            axis,
            k,
            rest_length,
            rest_sign: if rest >= 0.0 { 1.0 } else { -1.0 },
            damping,
            damper,
        }
    }
}

/// How a damper acts.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DamperKind {
    /// Along the spring's axis: D × (relative velocity of the points along it).
    Axis,
    /// Along the current vector between the points: D × (relative velocity along it).
    Vector,
}

/// A suspension element: a linear spring along one axis of the track frame, and a damper,
/// between a point of an upper body and a point of a lower body.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Link {
    /// What it is, for messages ("primary lateral spring", ...).
    pub name: &'static str,
    /// Upper body (car body or bogie).
    pub upper: usize,
    /// Lower body (bogie or wheelset).
    pub lower: usize,
    /// Point on the upper body, in its frame, from its centre (m).
    pub pu: [f64; 3],
    /// Point on the lower body, in its frame, from its centre (m).
    pub pl: [f64; 3],
    /// Nominal position of the upper centre minus that of the lower (m).
    pub dc: [f64; 3],
    /// Axis of the spring: 0 x, 1 y, 2 z.
    pub axis: usize,
    /// Stiffness (N/m).
    pub k: f64,
    /// Length of the spring along its axis when it carries no force (m).
    pub rest_length: f64,
    /// Sign of the axis component of the vector from the lower to the upper point at rest.
    pub rest_sign: f64,
    /// Damping (N·s/m).
    pub damping: f64,
    /// Direction of the damper.
    pub damper: DamperKind,
}
