//! Optional effects. A scene declares the ones it needs ([`Effects`]); the step runs
//! only those. Rolling costs nothing per step even when on (it scales the kick once
//! per tilt sample); the others are skipped by one branch per step when off, and
//! [`crate::physics::world::StepStats`] counts every run so a test can show that a
//! switched-off effect never executes.

use super::super::geometry::frame::Frame;
use super::super::scalar::Scalar;
use super::super::vec::Vec3;
use super::integrate::Kick;
use super::respond::restitution;

/// The effects a scene asks for. Walls, floor and restitution are always on.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Effects {
    /// Solid-sphere rolling: tangential acceleration is 5/7 of sliding.
    pub rolling: bool,
    /// Rolling resistance (a constant deceleration opposing motion, and a static
    /// threshold below which the marble stays put).
    pub friction: bool,
    /// The board's own rotation: fictitious forces in the board frame, where eq. 1
    /// then takes the surface at rest (`world::contact`'s doc).
    pub board_motion: bool,
    /// Holes in the floor: full 3-D motion (falling). Off: the plane only.
    pub holes: bool,
    /// Several marbles: marble–marble collisions.
    pub marbles: bool,
}

impl Effects {
    /// Every effect on.
    pub const ALL: Effects = Effects {
        rolling: true,
        friction: true,
        board_motion: true,
        holes: true,
        marbles: true,
    };
    /// Every effect off: walls, floor and restitution only.
    pub const NONE: Effects = Effects {
        rolling: false,
        friction: false,
        board_motion: false,
        holes: false,
        marbles: false,
    };
}

/// Rolling resistance for a marble on the floor (tangent plane x'–z').
///
/// `decel` is the deceleration per step (pitch/s per step, `c_rr·g_n·dt`). A marble
/// whose speed is below `decel` and whose tilt pull is too is held exactly still
/// (static friction): that is what keeps a resting marble from creeping. Otherwise
/// the kick gets a constant-magnitude component against the motion.
///
/// Speeds are scaled by 1/16 before squaring so that `v²` stays inside the narrowest
/// fixed format's range at the speed cap.
///
/// What depends on the pull alone is worked out once per pull ([`Drag::new`]; the
/// world keeps one): the step is left with the per-marble part ([`Drag::apply`]).
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub struct Drag<S> {
    /// The deceleration per step, `decel`.
    decel: S,
    /// The static threshold's square, `(decel/16)²`.
    limit2: S,
    /// `½·decel·dt`: the displacement the deceleration takes in a step.
    half_step: S,
    /// Event stepping's static threshold's square, `(decel/32)²` (its speeds
    /// are scaled by 1/32): one per pull, not two rounding shifts and a product
    /// every flight.
    flight_limit2: S,
    /// `decel·dt·2^10` (see [`Drag::flight`]): what a held direction's turn
    /// weighs against the squared speed.
    turn_weight: S,
}

impl<S: Scalar> Drag<S> {
    const SCALE: u32 = 4;

    /// The drag of a deceleration `decel` per step at `dt = 2^-k`.
    pub fn new(decel: S, k: u32) -> Self {
        let limit = decel.shr(Self::SCALE);
        let flight_limit = decel.shr(FLIGHT_SCALE);
        Drag {
            decel,
            limit2: limit.times(limit),
            half_step: decel.shr(k + 1),
            flight_limit2: flight_limit.times(flight_limit),
            turn_weight: if k <= TURN_LOG2 {
                decel.times(S::from_int(1 << (TURN_LOG2 - k)))
            } else {
                decel.shr(k - TURN_LOG2)
            },
        }
    }

    /// Applies the drag to a marble's velocity and kick.
    // Inlined into the step (its one caller), where the kick stays in registers.
    #[inline(always)]
    pub fn apply(&self, v: &mut Vec3<S>, kick: &mut Kick<S>) {
        let (vx, vz) = (v.x.shr(Self::SCALE), v.z.shr(Self::SCALE));
        let speed2 = vx.times(vx) + vz.times(vz);
        // Squares compared, and the direction from an inverse root: no root, no division.
        let (dx, dz, len2) = if speed2 > self.limit2 {
            (vx, vz, speed2)
        } else {
            let (ax, az) = (kick.dv.x.shr(Self::SCALE), kick.dv.z.shr(Self::SCALE));
            let pull2 = ax.times(ax) + az.times(az);
            if pull2 <= self.limit2 {
                v.x = S::ZERO;
                v.z = S::ZERO;
                kick.dv.x = S::ZERO;
                kick.dv.z = S::ZERO;
                kick.dp.x = S::ZERO;
                kick.dp.z = S::ZERO;
                return;
            }
            (ax, az, pull2)
        };
        let inv = len2.rsqrt();
        let (ux, uz) = (dx.times(inv), dz.times(inv));
        kick.dv.x -= self.decel.times(ux);
        kick.dv.z -= self.decel.times(uz);
        kick.dp.x -= self.half_step.times(ux);
        kick.dp.z -= self.half_step.times(uz);
    }
}

/// Event stepping scales rolling resistance's speeds by `2^-5` before squaring
/// them (128 pitch/s fits the narrowest format).
const FLIGHT_SCALE: u32 = 5;

/// `12·ε = 2^-TURN_LOG2` pitch, `ε` the most a held drag direction may move a
/// marble off the model's path in one flight ([`Drag::flight`]).
const TURN_LOG2: u32 = 10;

/// Half an interval of `len` steps; a whole step's (a quiet frame's) a
/// constant, without the rounding shift.
#[inline(always)]
fn half_of<S: Scalar>(len: S) -> S {
    if len == S::ONE {
        S::ONE.half()
    } else {
        len.half()
    }
}

/// What rolling resistance does to one event flight ([`Drag::flight`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DragFlight<S> {
    /// How long the drag's direction may be held (steps, at most the time left).
    pub len: S,
    /// When the speed along the drag's direction reaches zero (steps), if within
    /// `len`: an event.
    pub stop: Option<S>,
    /// The pull alone cannot beat the static threshold: a stopped marble stays
    /// put. Asked only where it is read, with a stop or of a marble at rest
    /// (else `false`).
    pub holds: bool,
    /// The drag's direction (x', z'; unit, or zero).
    pub dir: (S, S),
}

impl<S: Scalar> Drag<S> {
    /// Event stepping's rolling resistance over up to `rem` steps: adds the drag to
    /// the kick as a constant deceleration, which is exact as long as its direction
    /// is. It opposes the velocity, which the pull turns, so its direction is
    /// taken at the interval's midpoint (`v + pull·len/2`) and held for as long as
    /// that moves the marble at most `ε` off the model's path. Over an interval
    /// `T` in which the velocity turns by `θ = |a⊥|·T/|v|` the held direction is
    /// off by `θ·(t/T − ½)`, whose velocity error integrates to nothing and whose
    /// position error to `decel·θ·T²/12`: so `decel·|a⊥|·T³/(12|v|) ≤ ε`, in step
    /// units `decel·dt·|pull × v|·len³ ≤ 12ε·|v|²` with `12ε = 2^-10` pitch
    /// (1 µm at the default 12 mm pitch), halving the interval down to 1/4 step.
    /// The bound weighs the drag itself: at the default 1 % a slow marble turning
    /// under the board's pull keeps one direction a whole step, where a bound on
    /// the turn alone (1/4 rad) cut it to an eighth. A marble at rest stays at rest if
    /// the pull does not beat the drag (static friction), and otherwise starts along
    /// the pull, which keeps the direction fixed. Speeds are scaled by 1/32 before
    /// squaring (128 pitch/s fits).
    pub fn flight(&self, v: Vec3<S>, kick: &mut Kick<S>, rem: S) -> DragFlight<S> {
        // Along one axis (a marble rolling along a wall it is held on: the held
        // axis of its velocity and pull are zero), the same sums on that axis
        // alone (`along`): a fifth of the products, which the Cortex-M0 calls a
        // routine for.
        let one_axis = if v.x == S::ZERO && kick.dv.x == S::ZERO {
            Some((v.z, &mut kick.dv.z, &mut kick.dp.z, false))
        } else if v.z == S::ZERO && kick.dv.z == S::ZERO {
            Some((v.x, &mut kick.dv.x, &mut kick.dp.x, true))
        } else {
            None
        };
        if let Some((va, dv, dp, on_x)) = one_axis {
            let mut out = DragFlight {
                len: rem,
                stop: None,
                holds: true,
                dir: (S::ZERO, S::ZERO),
            };
            match self.along(va, dv, dp, rem) {
                Some((u, stop, holds)) => {
                    out.dir = if on_x { (u, S::ZERO) } else { (S::ZERO, u) };
                    (out.stop, out.holds) = (stop, holds);
                }
                // At rest and held: the plane's kick is dropped, both axes.
                None => {
                    kick.dv.x = S::ZERO;
                    kick.dv.z = S::ZERO;
                    kick.dp.x = S::ZERO;
                    kick.dp.z = S::ZERO;
                }
            }
            return out;
        }
        self.plane(v, kick, rem)
    }

    /// Whether static friction holds a marble at rest under the pull `(ax, az)`
    /// (per step, x' and z', the held faces' parts dropped): the test
    /// [`Drag::flight`] makes of a still marble, in the same sums (along one
    /// axis the other term is zero).
    #[inline]
    pub fn holds_at_rest(&self, ax: S, az: S) -> bool {
        let (qx, qz) = (ax.shr(FLIGHT_SCALE), az.shr(FLIGHT_SCALE));
        qx.times(qx) + qz.times(qz) <= self.flight_limit2
    }

    /// [`Drag::flight`] in the plane x'–z'.
    #[inline]
    fn plane(&self, v: Vec3<S>, kick: &mut Kick<S>, rem: S) -> DragFlight<S> {
        const SC: u32 = FLIGHT_SCALE;
        let (ax, az) = (kick.dv.x, kick.dv.z);
        let (qx, qz) = (ax.shr(SC), az.shr(SC));
        let holds = || self.holds_at_rest(ax, az);
        let mut out = DragFlight {
            len: rem,
            stop: None,
            holds: false,
            dir: (S::ZERO, S::ZERO),
        };
        let (dx, dz) = if v.x == S::ZERO && v.z == S::ZERO {
            if holds() {
                out.holds = true;
                kick.dv.x = S::ZERO;
                kick.dv.z = S::ZERO;
                kick.dp.x = S::ZERO;
                kick.dp.z = S::ZERO;
                return out;
            }
            (qx, qz)
        } else {
            let (sx, sz) = (v.x.shr(SC), v.z.shr(SC));
            let v2 = sx.times(sx) + sz.times(sz);
            let cross = (qx.times(sz) - qz.times(sx)).abs();
            // Halved down to a quarter of a step, not of the time left: a slow
            // marble under a strong sideways pull turns fast, and each interval is
            // a flight (a search, a budget unit). A held direction over 1/4 step is
            // off by at most what the pull turns the velocity in that time, a
            // drag of 2 % of g at most sideways, and taken at the midpoint its
            // error is of third order: a marble rolled across a slope stays within
            // 8 µm of the exact path (`tests/held_effects.rs`).
            let floor = S::ONE.shr(2).min(rem);
            // The bound's left side for the whole time left, then an eighth of it
            // a halving: three products, not three a halving; one at a step's
            // first flight, whose whole step left cubes to 1 (a product by 1 is
            // the same bits in every format).
            if out.len > floor {
                let mut off = self.turn_weight.times(cross);
                if rem != S::ONE {
                    off = off.times(rem.times(rem).times(rem));
                }
                while out.len > floor && off > v2 {
                    out.len = out.len.half();
                    off = off.shr(3);
                }
            }
            let half = half_of(out.len);
            let (mx, mz) = (
                v.x.sat_add(ax.times(half)).shr(SC),
                v.z.sat_add(az.times(half)).shr(SC),
            );
            if mx.times(sx) + mz.times(sz) > S::ZERO {
                (mx, mz)
            } else {
                (sx, sz)
            }
        };
        // Along an axis (a marble rolling along a wall it is held on: the held
        // axis of its velocity and pull are zero) the unit is that axis, exactly;
        // the reciprocal root would be a few LSB off it, at a root's cost.
        let axis = |d: S| if d > S::ZERO { S::ONE } else { -S::ONE };
        let (ux, uz) = if dz == S::ZERO {
            (if dx == S::ZERO { S::ZERO } else { axis(dx) }, S::ZERO)
        } else if dx == S::ZERO {
            (S::ZERO, axis(dz))
        } else {
            let inv = (dx.times(dx) + dz.times(dz)).rsqrt_fine();
            (dx.times(inv), dz.times(inv))
        };
        out.dir = (ux, uz);
        kick.dv.x = kick.dv.x.sat_add(-self.decel.times(ux));
        kick.dv.z = kick.dv.z.sat_add(-self.decel.times(uz));
        kick.dp.x -= self.half_step.times(ux);
        kick.dp.z -= self.half_step.times(uz);
        // The speed along the drag's direction, and how fast it changes (both
        // scaled like the squares: only their ratio matters).
        // The rate first: a marble the pull speeds up along the drag's
        // direction (half a maze's frames) cannot stop, and skips `along`.
        let rate = kick.dv.x.shr(SC).times(ux) + kick.dv.z.shr(SC).times(uz);
        if rate < S::ZERO {
            let along = v.x.shr(SC).times(ux) + v.z.shr(SC).times(uz);
            if along > S::ZERO && along + rate.times(out.len) <= S::ZERO {
                out.stop = Some(along.div(-rate).min(out.len));
                out.holds = holds();
            }
        }
        out
    }

    /// [`Drag::flight`] for a marble whose velocity and pull lie along one axis:
    /// `va` its velocity there, `dv` and `dp` that axis of the kick. The plane's
    /// sums with the other axis zero, term by term (each product with it is
    /// zero, the turn is none, so the interval is the time left), hence the same
    /// bits. Returns the unit along the axis (±1, or 0), the stop and whether the
    /// pull alone cannot beat the static threshold (asked with a stop, as the
    /// plane asks it); `None` for a marble at rest
    /// that stays put (the caller drops the plane's kick). Out of line: the
    /// event step's marble rolling along a wall asks it directly.
    #[inline(never)]
    pub fn along(&self, va: S, dv: &mut S, dp: &mut S, rem: S) -> Option<(S, Option<S>, bool)> {
        const SC: u32 = FLIGHT_SCALE;
        let a = *dv;
        // The pull scaled only where asked: at rest, or with a stop.
        let holds = || {
            let q = a.shr(SC);
            q.times(q) <= self.flight_limit2
        };
        let d = if va == S::ZERO {
            if holds() {
                return None;
            }
            a.shr(SC)
        } else {
            let s = va.shr(SC);
            let m = va.sat_add(a.times(half_of(rem))).shr(SC);
            if m.times(s) > S::ZERO {
                m
            } else {
                s
            }
        };
        if d == S::ZERO {
            // No direction: every product with the unit is zero, the kick
            // stays as it is and nothing slows.
            return Some((S::ZERO, None, false));
        }
        // The unit is ±1: each product with it (exact, in every format) is
        // the other factor or its negation, taken here without the product
        // (a library call on the Cortex-M0).
        let neg = d < S::ZERO;
        let by_u = |x: S| if neg { -x } else { x };
        *dv = dv.sat_add(-by_u(self.decel));
        *dp -= by_u(self.half_step);
        // The rate first, as the plane's: a marble sped up cannot stop.
        let rate = by_u(dv.shr(SC));
        let (mut stop, mut held) = (None, false);
        if rate < S::ZERO {
            let along = by_u(va.shr(SC));
            if along > S::ZERO && along + rate.times(rem) <= S::ZERO {
                stop = Some(along.div(-rate).min(rem));
                held = holds();
            }
        }
        let u = if neg { -S::ONE } else { S::ONE };
        Some((u, stop, held))
    }

    /// At a stop: the velocity's part along the drag's direction `dir` is spent;
    /// what is left is dropped too when it is slower than the drag takes away in
    /// 1/1024 of a step (rounding's residue, which would otherwise stop again at
    /// once), or when `holds` (static friction keeps it).
    pub fn stopped(&self, v: &mut Vec3<S>, dir: (S, S), holds: bool) {
        let along = v.x.times(dir.0) + v.z.times(dir.1);
        v.x -= along.times(dir.0);
        v.z -= along.times(dir.1);
        let lim = self.decel.shr(10);
        if holds || (v.x.abs() <= lim && v.z.abs() <= lim) {
            v.x = S::ZERO;
            v.z = S::ZERO;
        }
    }
}

/// The board's rotation as the physics needs it, in the tile frame.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub struct BoardMotion<S> {
    /// Angular velocity times `dt` (radians per step).
    pub omega: Vec3<S>,
    /// Angular acceleration times `dt²` (radians per step²).
    pub omega_dot: Vec3<S>,
    /// The point the board turns about (tile frame, pitch).
    pub pivot: Vec3<S>,
}

impl<S: Scalar> BoardMotion<S> {
    /// The rotation from frame `prev` to frame `cur` (eq. 4 frames of the board),
    /// expressed in `prev`'s tile frame, as a small rotation vector (radians):
    /// `Bₚᵀ B_c ≈ I + [θ]×`.
    pub(crate) fn rotation_between(prev: &Frame<S>, cur: &Frame<S>) -> Vec3<S> {
        // Columns of B_cur in prev's tile coordinates (eq. 4 applied to directions).
        let cx = prev.dir_to_tile(cur.basis[0]);
        let cy = prev.dir_to_tile(cur.basis[1]);
        let cz = prev.dir_to_tile(cur.basis[2]);
        Vec3::new(
            (cy.z - cz.y).half(),
            (cz.x - cx.z).half(),
            (cx.y - cy.x).half(),
        )
    }

    /// Event stepping: how long (steps, at most `rem`) the fictitious accelerations
    /// may be held constant. They change with the marble's position and velocity,
    /// by about `|ω|` of themselves per radian turned; holding them while the board
    /// turns by at most 1/64 rad (halving the interval down to `rem/16`) keeps that
    /// change under 2 % of a term that is itself small. A still board: the whole
    /// interval.
    pub(crate) fn flight_len(&self, rem: S) -> S {
        let w = self
            .omega
            .x
            .abs()
            .max(self.omega.y.abs())
            .max(self.omega.z.abs());
        let mut len = rem;
        let floor = rem.shr(4);
        while len > floor && w.times(len) > S::ONE.shr(6) {
            len = len.half();
        }
        len
    }

    /// The fictitious accelerations of the rotating board frame acting on a marble at
    /// `p` moving at `v_step` (pitch/step): Euler `−ω̇×r`, centrifugal `−ω×(ω×r)` and
    /// Coriolis `−2ω×v`, as a kick at step `dt = 2^-k`.
    // Inlined into the step: the flat maze drops the y' part, which then is never
    // computed (a quarter of the products).
    #[inline(always)]
    pub fn kick(&self, p: Vec3<S>, v_step: Vec3<S>, k: u32) -> Kick<S> {
        let r = p - self.pivot;
        let euler = -self.omega_dot.cross(r);
        let centrifugal = -self.omega.cross(self.omega.cross(r));
        // Doubled by a sum, the same bits as the product by 2 it replaces
        // (both wrap, and overflow-checked builds check both at 2³⁰ LSB):
        // three products a flight fewer, about 70 Cortex-M0 instructions.
        let half = self.omega.cross(v_step);
        let coriolis = -(half + half);
        let a = euler + centrifugal + coriolis; // pitch/step²
        Kick {
            dv: a.shl(k),
            dp: a.shr(1),
        }
    }
}

/// Two equal marbles in contact along unit normal `n` (from 1 to 2), in the contact
/// solver's units (pitch/T). Returns the new velocities and, when they bounce (eq. 1
/// with `e`, closing faster than `threshold`), their closing speed (else zero: for
/// the impacts a game clicks on). The pair's relative motion obeys eq. 1 with the
/// other marble as the "board", each taking half of the momentum change.
pub(crate) fn marble_pair<S: Scalar>(
    v1: Vec3<S>,
    v2: Vec3<S>,
    n: Vec3<S>,
    e: S,
    threshold: S,
) -> (Vec3<S>, Vec3<S>, S) {
    let vn = (v2 - v1).dot(n);
    if vn >= S::ZERO {
        return (v1, v2, S::ZERO);
    }
    let e = if -vn <= threshold { S::ZERO } else { e };
    // Eq. 1 for marble 2 against marble 1: the change it would get off an immovable
    // board, halved because the "board" recoils with equal mass.
    let dv = (restitution(v2, v1, n, e) - v2).shr(1);
    let bounce = if e > S::ZERO { -vn } else { S::ZERO };
    (v1 - dv, v2 + dv, bounce)
}

#[cfg(test)]
mod tests {
    use super::*;

    type S = fixed::types::I8F24;

    /// The one-axis sums give the plane's bits: every velocity and pull along x'
    /// or z' (the other axis zero), moving, at rest, slow, fast, pulled with or
    /// against the motion, with intervals from a step down to a sliver.
    #[test]
    fn one_axis_is_the_plane_to_the_bit() {
        let f = S::from_num;
        let values = [
            0.0, 1e-7, -1e-7, 3e-6, -3e-6, 0.0009, -0.0009, 0.004, -0.004, 0.02, -0.02, 0.3, -0.3,
            1.7, -1.7, 60.0, -60.0, 127.0, -127.0,
        ];
        let pulls = [
            0.0, 2e-6, -2e-6, 1e-4, -1e-4, 0.003, -0.003, 0.05, -0.05, 0.9, -0.9,
        ];
        let mut compared = 0;
        for decel in [0.0, 0.001, 0.004, 0.05] {
            let drag = Drag::<S>::new(f(decel), 7);
            for &va in &values {
                for &aa in &pulls {
                    for rem in [1.0, 0.5, 0.013] {
                        for on_x in [false, true] {
                            let (v, dv, dp) = if on_x {
                                (
                                    Vec3::new(f(va), S::ZERO, S::ZERO),
                                    Vec3::new(f(aa), S::ZERO, S::ZERO),
                                    Vec3::new(f(aa / 256.0), S::ZERO, f(1e-7)),
                                )
                            } else {
                                (
                                    Vec3::new(S::ZERO, S::ZERO, f(va)),
                                    Vec3::new(S::ZERO, S::ZERO, f(aa)),
                                    Vec3::new(f(-1e-7), S::ZERO, f(aa / 256.0)),
                                )
                            };
                            let (mut k1, mut k2) = (Kick { dv, dp }, Kick { dv, dp });
                            let one = drag.flight(v, &mut k1, f(rem));
                            let plane = drag.plane(v, &mut k2, f(rem));
                            assert_eq!(
                                one, plane,
                                "v {va}, pull {aa}, rem {rem}, x {on_x}, decel {decel}"
                            );
                            assert_eq!(
                                (k1.dv, k1.dp),
                                (k2.dv, k2.dp),
                                "v {va}, pull {aa}, rem {rem}"
                            );
                            compared += 1;
                        }
                    }
                }
            }
        }
        assert_eq!(compared, 4 * 19 * 11 * 3 * 2);
    }

    /// A marble rolling along a wall it is held on moves along one axis: the drag
    /// takes its whole deceleration off that axis and nothing off the other, to the
    /// bit (a unit from a reciprocal root would be a few LSB short of one).
    #[test]
    fn along_an_axis_the_drag_is_the_whole_deceleration() {
        let f = S::from_num;
        let drag = Drag::<S>::new(f(0.004), 7);
        // (velocity x, z; pull x, z; the drag's direction): moving, moving against
        // the pull, starting from rest along the pull.
        let cases = [
            ((0.5, 0.0), (0.02, 0.0), (1, 0)),
            ((0.0, -0.3), (0.0, 0.01), (0, -1)),
            ((-0.7, 0.0), (0.0, 0.0), (-1, 0)),
            ((0.0, 0.0), (0.0, -0.2), (0, -1)),
        ];
        for ((vx, vz), (ax, az), (ux, uz)) in cases {
            let v = Vec3::new(f(vx), S::ZERO, f(vz));
            let (dv, dp) = (
                Vec3::new(f(ax), S::ZERO, f(az)),
                Vec3::new(f(ax / 2.0), S::ZERO, f(az / 2.0)),
            );
            let mut kick = Kick { dv, dp };
            let d = drag.flight(v, &mut kick, S::ONE);
            let (ux, uz) = (S::from_num(ux), S::from_num(uz));
            assert_eq!(d.dir, (ux, uz), "v ({vx}, {vz}), pull ({ax}, {az})");
            assert_eq!(kick.dv.x, dv.x - drag.decel * ux, "v ({vx}, {vz})");
            assert_eq!(kick.dv.z, dv.z - drag.decel * uz, "v ({vx}, {vz})");
            assert_eq!(kick.dp.x, dp.x - drag.half_step * ux, "v ({vx}, {vz})");
            assert_eq!(kick.dp.z, dp.z - drag.half_step * uz, "v ({vx}, {vz})");
        }
    }
}
