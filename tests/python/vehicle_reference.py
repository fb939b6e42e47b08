"""An independent reference model of the Cooperrider car, for cross-checking Vehicle.fmu.

Written in numpy/scipy from the specification alone (MODELS.md, section 5) by a reviewer who did
not read the Rust implementation: one car body, two bogie frames, four wheelsets, linear
suspension elements acting along one axis each, wheel-rail contact from a tabulated contact
geometry (cubic splines), Kalker's linear creep law saturated by Shen-Hedrick-Elkins, curve and
cant loads, the wheelsets' gyroscopic moments. Only the steady states are used by the tests:
the equilibrium (on a curve reached by continuation in curvature and cant), the Jacobian by
central differences and its eigenvalues, and the wheels' contact forces Y and Q.

Where MODELS.md leaves room, the model makes the FMU's choices (docs/src/reference/models.md,
Vehicle, "Modelling choices"):

- the wheelset's roll moment is that of the vertical contact forces about the lever arm aw
  (with the roll corrections); the lateral contact forces, which act r below the axle, add none.
  Here the vertical force's arm is the contact point's y turned by the roll,
  s aw cos(phi) + r sin(phi), where the FMU writes s aw (Z - Y phi): the two differ in terms of
  second order in the small roll, below 0.001 % in the steady wheel loads. Switchable:
  `Car(..., roll_lateral_moment=True)` adds the lateral forces' moment (the physical reading,
  the FMU's `roll_moment = 1`);
- the creep forces are turned into the track frame by the wheelset's yaw psi as well as by
  delta +- phi (the spin torque uses the turned lateral force);
- the suspension's lever arms turn with their bodies (small rotations, I + skew);
- the pitch equation divides by Iy (not by Ix as the reference implementation);
- the nominal spin Omega0 is v over the table's rolling radius at y = 0 (not v/r0);
- the gyroscopic moments are MODELS.md's, (Iy - Iz) Omega psi' in roll and (Ix - Iy) phi' Omega
  in yaw.

State vector (66): car body and bogie frames [y, z, phi, chi, psi] and their rates, 10 each
(body 0 the car body, 1 the leading bogie at x = +u1, 2 the trailing one at x = -u1), then the
wheelsets W1..W4 at x = u1 + u2, u1 - u2, -u1 + u2, -u1 - u2 (bodies 3..6) with
[y, z, phi, psi] and their rates and the spin perturbation beta, 9 each. Track-following frame:
x forward, y to the left, z up. A curve with R > 0 turns to the right (-y); cant > 0 raises the
left rail. Units SI throughout (m, rad, s, kg, N).
"""
import io

import numpy as np
from scipy.interpolate import CubicSpline
from scipy.optimize import brentq

# MODELS.md 5.2-5.6: masses [kg], inertias [kg m^2], lengths [m], stiffnesses [N/m],
# dampings [N s/m], friction coefficient [-], shear modulus [Pa], gravity [m/s^2].
PARAMETERS = dict(
    m_c=44388.0, Ix_c=2.8e5, Iy_c=5e5, Iz_c=5e5,
    m_b=2918.9, Ix_b=6780.0, Iy_b=6780.0, Iz_b=6780.0,
    m_w=1022.0, Ix_w=678.0, Iy_w=80.0, Iz_w=678.0,
    r0=0.425, h1=0.0762, h2=1.5584, a=0.75, l1=0.3, l2=0.3, l3=0.3,
    v1=0.6488, v2=0.3, v4=0.3096, u1=7.5, u2=1.074, x1=0.349,
    s1=0.62, s2=0.6584, s3=0.68, s4=0.759,
    k1=1.823e6, k2=3.646e6, k3=3.646e6, k4=1.823e5, k5=3.333e5, k6=9.0335e5,
    D1=2e4, D2=2.92e4, D3=0.0, D4=0.0, D5=0.0, D6=1.66669e5,
    mu=0.15, G=2.1e11 / (2 * (1 - 0.27)), g=9.81,
)

N_STATES = 66
WHEELS = ("1L", "1R", "2L", "2R", "3L", "3R", "4L", "4R")
# Contact table columns, left wheel: normal force N0 [N], contact angle delta [rad], ellipse
# semi-axes a, b [m], contact point's lateral position on the wheel aw [m], rolling radius r [m],
# Kalker coefficients C11, C22, C23 [-], vertical contact coordinate zc [m], penetration q0 [m].
TABLE_COLUMNS = ("N0", "delta", "a", "b", "aw", "r", "c11", "c22", "c23", "zc", "q0")


def load_contact_table(path):
    """The contact table (CSV of MODELS.md 5.8): its y grid [m] and a cubic spline of the
    columns TABLE_COLUMNS over y."""
    with open(path) as f:
        lines = [line for line in f if not line.startswith("#")]
    data = np.genfromtxt(io.StringIO("".join(lines)), delimiter=",", names=True)
    values = np.column_stack([data[c] for c in TABLE_COLUMNS])
    return data["y"], CubicSpline(data["y"], values, axis=0)


class Car:
    """The car on a track of radius `R` [m] (inf = straight) and cant `cant` [rad], at speed
    `v` [m/s] (attributes, set them before evaluating). `parameters` override PARAMETERS."""

    def __init__(self, table, roll_lateral_moment=False, **parameters):
        self.p = dict(PARAMETERS, **parameters)
        self.roll_lateral_moment = roll_lateral_moment
        table_y, self.table = load_contact_table(table)
        self.y_max = table_y[-1]  # beyond: derailment [m]
        p = self.p
        # Nominal centres: x [m], height above rail level [m]; mass and inertias per body.
        self.X = np.array([0.0, p["u1"], -p["u1"], p["u1"] + p["u2"], p["u1"] - p["u2"],
                           -p["u1"] + p["u2"], -p["u1"] - p["u2"]])
        self.Z = np.array([p["r0"] + p["h1"] + p["h2"]] + [p["r0"] + p["h1"]] * 2
                          + [p["r0"]] * 4)
        self.m = np.array([p["m_c"]] + [p["m_b"]] * 2 + [p["m_w"]] * 4)
        self.Ix = np.array([p["Ix_c"]] + [p["Ix_b"]] * 2 + [p["Ix_w"]] * 4)
        self.Iy = np.array([p["Iy_c"]] + [p["Iy_b"]] * 2 + [p["Iy_w"]] * 4)
        self.Iz = np.array([p["Iz_c"]] + [p["Iz_b"]] * 2 + [p["Iz_w"]] * 4)
        self._build_elements()
        # Nominal spin reference radius: the table's rolling radius at y = 0 [m].
        self.r_spin = float(self.table(0.0)[TABLE_COLUMNS.index("r")])
        self.R = np.inf  # [m]
        self.cant = 0.0  # [rad]
        self.v = 40.0  # [m/s]

    def _build_elements(self):
        """The suspension elements of MODELS.md 5.4: body A, its attachment point, body B, its
        point (local frames, relative to the centres), axis (0 x, 1 y, 2 z), stiffness, damping,
        preload [N], pushing A up and B down."""
        p = self.p
        primary_preload = (p["m_c"] + 2 * p["m_b"]) * p["g"] / 8
        secondary_preload = p["m_c"] * p["g"] / 4
        yaw_y = p["a"] + p["l1"] + p["l2"] + p["l3"] / 2
        elements = []
        for bogie, sx in ((1, 1.0), (2, -1.0)):
            for s in (1.0, -1.0):
                # secondary lateral (y), secondary vertical (z), yaw spring and damper (x)
                elements.append((0, (sx * p["u1"], s * (p["a"] + p["l1"] + p["l2"] + p["l3"]),
                                     -(p["h2"] - p["s2"])),
                                 bogie, (0, s * (p["a"] + p["l1"] + p["l2"]), p["s2"]),
                                 1, p["k4"], p["D2"], 0.0))
                elements.append((0, (sx * p["u1"], s * p["s3"], -p["v4"]),
                                 bogie, (0, s * p["s3"], p["v1"] + p["v2"]),
                                 2, p["k5"], p["D1"], secondary_preload))
                elements.append((0, (sx * (p["u1"] + p["s4"]), s * yaw_y, -p["h2"]),
                                 bogie, (0, s * yaw_y, 0),
                                 0, p["k6"], p["D6"], 0.0))
            wheelsets = (3, 4) if bogie == 1 else (5, 6)
            for wheelset, e in zip(wheelsets, (1.0, -1.0)):
                for s in (1.0, -1.0):
                    # primary lateral (y), primary vertical (z), primary longitudinal (x)
                    elements.append((bogie, (e * p["u2"], s * (p["a"] + p["l1"]), -p["h1"]),
                                     wheelset, (0, s * p["a"], 0),
                                     1, p["k1"], p["D5"], 0.0))
                    elements.append((bogie, (e * p["u2"], s * p["s1"], p["v1"]),
                                     wheelset, (0, s * p["s1"], 0),
                                     2, p["k3"], p["D4"], primary_preload))
                    elements.append((bogie, (e * p["x1"], s * p["s1"], -p["h1"]),
                                     wheelset, (0, s * p["s1"], 0),
                                     0, p["k2"], p["D3"], 0.0))
        self.el_A = np.array([e[0] for e in elements])
        self.el_pA = np.array([e[1] for e in elements], float)
        self.el_B = np.array([e[2] for e in elements])
        self.el_pB = np.array([e[3] for e in elements], float)
        self.el_axis = np.array([e[4] for e in elements])
        self.el_k = np.array([e[5] for e in elements])
        self.el_D = np.array([e[6] for e in elements])
        self.el_preload = np.array([e[7] for e in elements])
        self.el_rows = np.arange(len(elements))
        # Rest component of each element along its axis [m].
        centres = np.column_stack([self.X, np.zeros(7), self.Z])
        rest = (centres[self.el_A] + self.el_pA) - (centres[self.el_B] + self.el_pB)
        self.el_rest = rest[self.el_rows, self.el_axis]

    @staticmethod
    def _unpack(x):
        """Positions and rates per body as [y, z, phi, chi, psi] (wheelset chi = 0), and beta."""
        pos = np.zeros((7, 5))
        vel = np.zeros((7, 5))
        beta = np.zeros(4)
        for i in range(3):
            pos[i] = x[10 * i:10 * i + 5]
            vel[i] = x[10 * i + 5:10 * i + 10]
        for j in range(4):
            o = 30 + 9 * j
            pos[3 + j] = [x[o], x[o + 1], x[o + 2], 0.0, x[o + 3]]
            vel[3 + j] = [x[o + 4], x[o + 5], x[o + 6], 0.0, x[o + 7]]
            beta[j] = x[o + 8]
        return pos, vel, beta

    @staticmethod
    def _pack_derivative(acc, vel, beta_rate):
        dx = np.zeros(N_STATES)
        for i in range(3):
            dx[10 * i:10 * i + 5] = vel[i]
            dx[10 * i + 5:10 * i + 10] = acc[i]
        for j in range(4):
            o = 30 + 9 * j
            dx[o:o + 3] = vel[3 + j][:3]
            dx[o + 3] = vel[3 + j][4]
            dx[o + 4:o + 7] = acc[3 + j][:3]
            dx[o + 7] = acc[3 + j][4]
            dx[o + 8] = beta_rate[j]
        return dx

    @property
    def curvature(self):
        return 1.0 / self.R  # [1/m]

    def contact(self, pos, vel, beta):
        """Contact forces per wheelset (track frame): force [N] (x, y, z) and moment [N m]
        (roll, 0, yaw), 4 x 3 each; spin torques [N m] (4); and per wheel the lateral force
        Y_<wheel> of the wheel on the rail (+ to the left) and the vertical force Q_<wheel> [N]."""
        p = self.p
        v = self.v
        kappa = self.curvature
        cos_cant = np.cos(self.cant)
        ys = pos[3:, 0]
        if np.any(np.abs(ys) > self.y_max):
            raise RuntimeError(f"derailment: wheelset y = {ys} m beyond the contact table")
        # Left wheels at +y, right wheels at -y: rows 0-3 and 4-7.
        rows = self.table(np.concatenate([ys, -ys]))
        force = np.zeros((4, 3))
        moment = np.zeros((4, 3))
        spin = np.zeros(4)
        wheel_forces = {}
        for j in range(4):
            y, z, phi, _, psi = pos[3 + j]
            yd, zd, phid, _, psid = vel[3 + j]
            # b = +u2 for the leading wheelset of a bogie, -u2 for the trailing one.
            e = 1.0 if j in (0, 2) else -1.0
            spin_speed = v / self.r_spin + beta[j]  # [rad/s]
            yaw = psi + e * p["u2"] * kappa  # psi + b/R [rad]
            for s, row in ((1.0, rows[j]), (-1.0, rows[4 + j])):
                N0, delta, semi_a, semi_b, aw, r, C11, C22, C23, _, q0 = row
                sphi = s * phi
                # Extra penetration from wheelset z and roll (with the roll corrections).
                roll_drop = ((r - aw * np.tan(sphi)) * np.sin(sphi) + aw / np.cos(sphi) - aw
                             - r * sphi)
                angle = delta + sphi
                penetration = -roll_drop * np.sin(angle) - (z + sphi * aw) * np.cos(angle)
                bracket = 1 + penetration / q0
                N = N0 * bracket**1.5 if bracket > 0 else 0.0
                scale = (N / N0) ** (1 / 3) if N > 0 else 0.0
                semi_a *= scale
                semi_b *= scale
                # Creepages (MODELS.md 5.6; the right wheel mirrored by s).
                xi_x = (v + yaw * yd + r * (yaw * phid - spin_speed) - s * aw * psid
                        + s * p["a"] * v * cos_cant * kappa) / v
                xi_y = ((-v * yaw * (1 + s * p["a"] * cos_cant * kappa) + phi * zd + yd
                         + r * phid) * np.cos(delta)
                        + s * (-phi * yd + zd + s * aw * phid) * np.sin(delta)) / v
                xi_s = (-s * (spin_speed - yaw * phid) * np.sin(delta) + psid * np.cos(delta)) / v
                # Kalker linear, saturated by Shen-Hedrick-Elkins [N].
                Gab = p["G"] * semi_a * semi_b
                Fx = -Gab * C11 * xi_x
                Fy = -Gab * (C22 * xi_y + np.sqrt(semi_a * semi_b) * C23 * xi_s)
                F_abs = np.hypot(Fx, Fy)
                if N > 0 and F_abs > 0:
                    u = F_abs / (p["mu"] * N)
                    F_sat = p["mu"] * N * (u - u * u / 3 + u**3 / 27) if u < 3 else p["mu"] * N
                    Fx *= F_sat / F_abs
                    Fy *= F_sat / F_abs
                else:
                    Fx = Fy = 0.0
                # Into the track frame: by delta + phi, then by the yaw psi.
                Fz_track = N * np.cos(angle) + s * Fy * np.sin(angle)
                Fy_track = -s * N * np.sin(angle) + Fy * np.cos(angle) + psi * Fx
                Fx_track = Fx - psi * Fy * np.cos(angle)
                # Contact point relative to the axle centre (y, z) [m].
                arm_y = s * aw * np.cos(phi) + r * np.sin(phi)
                arm_z = s * aw * np.sin(phi) - r * np.cos(phi)
                roll = arm_y * Fz_track
                if self.roll_lateral_moment:
                    roll -= arm_z * Fy_track
                force[j] += (Fx_track, Fy_track, Fz_track)
                moment[j] += (roll, 0.0, -arm_y * Fx_track)
                spin[j] += -r * (Fx + psi * Fy_track)
                wheel = f"{j + 1}{'L' if s > 0 else 'R'}"
                wheel_forces["Y_" + wheel] = -Fy_track
                wheel_forces["Q_" + wheel] = Fz_track
        return force, moment, spin, wheel_forces

    def _evaluate(self, x):
        p = self.p
        v = self.v
        pos, vel, beta = self._unpack(x)
        force = np.zeros((7, 3))
        moment = np.zeros((7, 3))
        angles = pos[:, 2:5]
        rates = vel[:, 2:5]
        # Suspension: lever arms turned with their bodies.
        A, B, pA, pB = self.el_A, self.el_B, self.el_pA, self.el_pB
        arm_A = pA + np.cross(angles[A], pA)
        arm_B = pB + np.cross(angles[B], pB)
        centres = np.column_stack([self.X, pos[:, 0], self.Z + pos[:, 1]])
        centre_rates = np.column_stack([np.zeros(7), vel[:, 0], vel[:, 1]])
        gap = centres[A] + arm_A - centres[B] - arm_B
        gap_rate = (centre_rates[A] + np.cross(rates[A], pA) - centre_rates[B]
                    - np.cross(rates[B], pB))
        length = gap[self.el_rows, self.el_axis]
        f = (self.el_k * (np.abs(length) - np.abs(self.el_rest)) * np.sign(self.el_rest)
             + self.el_D * gap_rate[self.el_rows, self.el_axis])
        force_on_A = np.zeros((len(A), 3))
        force_on_A[self.el_rows, self.el_axis] = -f
        force_on_A[:, 2] += self.el_preload
        moment_on_A = np.cross(arm_A, force_on_A)
        moment_on_B = np.cross(arm_B, -force_on_A)
        for i in range(7):
            on_A = A == i
            on_B = B == i
            force[i] += force_on_A[on_A].sum(0) - force_on_A[on_B].sum(0)
            moment[i] += moment_on_A[on_A].sum(0) + moment_on_B[on_B].sum(0)
        # Gravity and curve loads.
        kappa = self.curvature
        cos_cant, sin_cant = np.cos(self.cant), np.sin(self.cant)
        force[:, 1] += self.m * (v * v * kappa * cos_cant - p["g"] * sin_cant)
        force[:, 2] += self.m * (-p["g"] * cos_cant - v * v * kappa * sin_cant)
        contact_force, contact_moment, spin, wheel_forces = self.contact(pos, vel, beta)
        force[3:] += contact_force
        moment[3:] += contact_moment
        # Wheelsets' gyroscopic moments (MODELS.md 5.7).
        spin_speed = v / self.r_spin + beta
        psid = vel[3:, 4]
        phid = vel[3:, 2]
        moment[3:, 0] += (-p["Ix_w"] * spin_speed * v * cos_cant * kappa
                          + (p["Iy_w"] - p["Iz_w"])
                          * (-spin_speed * v * cos_cant * kappa + spin_speed * psid))
        moment[3:, 2] += (p["Ix_w"] - p["Iy_w"]) * phid * spin_speed
        acc = np.column_stack([force[:, 1] / self.m, force[:, 2] / self.m, moment[:, 0] / self.Ix,
                               moment[:, 1] / self.Iy, moment[:, 2] / self.Iz])
        acc[3:, 3] = 0.0
        return self._pack_derivative(acc, vel, spin / p["Iy_w"]), wheel_forces

    def rhs(self, x):
        """dx/dt at the state x."""
        return self._evaluate(x)[0]

    def wheel_forces(self, x):
        """{'Y_1L': ..., 'Q_1L': ..., ...} [N] at the state x."""
        return self._evaluate(x)[1]

    def jacobian(self, x, h=1e-7):
        """d(rhs)/dx by central differences of step h."""
        J = np.zeros((N_STATES, N_STATES))
        for i in range(N_STATES):
            xp = x.copy()
            xp[i] += h
            xm = x.copy()
            xm[i] -= h
            J[:, i] = (self.rhs(xp) - self.rhs(xm)) / (2 * h)
        return J

    def equilibrium(self, x0=None, tol=1e-10, max_iter=30):
        """Newton's method (least squares steps, step halving) from x0 (default: the nominal
        state) on rhs(x) = 0; returns the state and max |rhs|."""
        x = np.zeros(N_STATES) if x0 is None else x0.copy()
        for _ in range(max_iter):
            f = self.rhs(x)
            if np.max(np.abs(f)) < tol:
                break
            step = np.linalg.lstsq(self.jacobian(x), -f, rcond=None)[0]
            lam = 1.0
            for _ in range(30):
                x_new = x + lam * step
                try:
                    if np.linalg.norm(self.rhs(x_new)) < np.linalg.norm(f) or lam < 1e-3:
                        break
                except RuntimeError:  # beyond the table: shorter step
                    pass
                lam *= 0.5
            x = x_new
        return x, np.max(np.abs(self.rhs(x)))

    def curve_equilibrium(self, R, cant, steps=8):
        """The steady state on a curve of radius R [m] and cant [rad], by continuation from
        straight track: curvature and cant raised in `steps` equal steps, each equilibrium
        starting from the previous. Leaves the car on that curve; returns the state and
        max |rhs|."""
        x = np.zeros(N_STATES)
        for i in range(1, steps + 1):
            f = i / steps
            self.R = R / f
            self.cant = cant * f
            x, residual = self.equilibrium(x, tol=1e-9, max_iter=40)
        return x, residual


def max_growth_rate(car, v):
    """Largest real part [1/s] of the eigenvalues of the Jacobian at the centred equilibrium of
    `car` at speed v [m/s]."""
    car.v = v
    x, _ = car.equilibrium()
    return np.max(np.linalg.eigvals(car.jacobian(x)).real)


def hopf_speed(car, lo=5.0, hi=300.0, n=30, xtol=1e-3):
    """Linear (Hopf) critical speed [m/s]: the first of n equally spaced speeds in [lo, hi] at
    which the centred equilibrium is unstable, refined by Brent's method to xtol; None if it is
    stable throughout."""
    previous = None
    for v in np.linspace(lo, hi, n):
        if max_growth_rate(car, v) > 0:
            if previous is None:
                return v
            return brentq(lambda u: max_growth_rate(car, u), previous, v, xtol=xtol)
        previous = v
    return None
