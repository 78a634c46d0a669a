//! Times of impact for event stepping: when, inside a step, a marble flying the
//! closed form first touches a tile, the lid or another marble.
//!
//! Between two events the acceleration is constant, so the centre follows
//! `c(σ) = p + u·σ + h·σ²` with `σ` in steps (`dt = 2^-k` s), `u = v·dt` and
//! `h = ½·a·dt²` — the integrator's own exact solution (`integrate`), evaluated at
//! any instant instead of only at the end of the step ([`Segment`]).
//!
//! * **A plane** (a tile's face, the lid) is reached when the distance along its
//!   normal — a parabola too — has closed to `r`: a quadratic, solved in closed form
//!   by [`first_root`] (one square root, one division, no iteration).
//! * **A tile** (a box, rounded by the radius at its edges and corners) is convex.
//!   The plane through the box's point closest to the centre, perpendicular to the
//!   offset between them, separates them: the centre cannot touch the rounded box
//!   before it has crossed that plane moved out by `r`. The crossing time is a safe
//!   advance, and repeating it from there converges on the contact (conservative
//!   advancement along separating planes, as continuous collision detection does
//!   for convex shapes): for a face in one advance (the plane *is* the face), for an
//!   edge or a corner in a few. After [`CA_STEPS`] the search stops at a time
//!   short of the contact ([`Toi::Later`]) and the caller asks again from there.
//! * **Another marble** is a box of size zero with radius `2r` in the pair's
//!   relative motion, itself such a parabola.
//!
//! Every answer is no later than the first contact (up to rounding, a few LSB of
//! depth): a contact is never skipped, however fast the marble and however thin the
//! tile — no tunnelling by construction, with no bound on the step or the speed.
//!
//! All quantities are in step units (pitch, pitch/step, pitch/step²): with the
//! event step's pull bound (`a·dt` under the format's 128 pitch/s) and its speed
//! bound (128 pitch/s), `|u| ≤ 1`, `|h| ≤ ½` at 2^7 steps/s and every square here
//! stays below 16, inside the narrowest fixed format.

use super::super::geometry::narrowphase::{offset, unit, Contact, Feature};
use super::super::geometry::tiles::Aabb;
use super::super::scalar::Scalar;
use super::super::vec::Vec3;

/// Separating-plane advances before a search gives up with [`Toi::Later`].
pub(crate) const CA_STEPS: u32 = 8;

/// Constant-acceleration flight from a known state: the closed form between events.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Segment<S> {
    /// Centre at the start (pitch).
    pub p: Vec3<S>,
    /// Velocity at the start (pitch/s).
    pub v: Vec3<S>,
    /// `v·dt`: the velocity in pitch per step.
    pub u: Vec3<S>,
    /// `a·dt`: velocity gained per step (pitch/s).
    pub dv: Vec3<S>,
    /// `½·a·dt²`: displacement gained from rest in one step (pitch).
    pub h: Vec3<S>,
}

impl<S: Scalar> Segment<S> {
    /// The flight from `p` at `v` (pitch/s) under the kick `(dv, h)` of a step
    /// `2^-k` s.
    #[inline]
    pub fn new(p: Vec3<S>, v: Vec3<S>, dv: Vec3<S>, h: Vec3<S>, k: u32) -> Self {
        Segment {
            p,
            v,
            u: v.shr(k),
            dv,
            h,
        }
    }

    /// A marble standing still at `p`.
    pub const fn still(p: Vec3<S>) -> Self {
        Segment {
            p,
            v: Vec3::ZERO,
            u: Vec3::ZERO,
            dv: Vec3::ZERO,
            h: Vec3::ZERO,
        }
    }

    /// The centre after `s` steps. A whole step is `integrate::advance`'s sum
    /// exactly; a part of one rounds `h·s²` away from zero, as the integrator's
    /// kick is (short of the pull it would add energy).
    #[inline]
    pub fn pos_at(&self, s: S) -> Vec3<S> {
        if s == S::ONE {
            return self.p + (self.u + self.h);
        }
        let s2 = up(s, s);
        let bend = Vec3::new(up(self.h.x, s2), up(self.h.y, s2), up(self.h.z, s2));
        self.p + (self.u.scale(s) + bend)
    }

    /// The velocity (pitch/s) after `s` steps, saturating at the format's range
    /// (the event step's only speed limit).
    #[inline]
    pub fn vel_at(&self, s: S) -> Vec3<S> {
        let dv = if s == S::ONE {
            self.dv
        } else {
            self.dv.scale(s)
        };
        Vec3::new(
            self.v.x.sat_add(dv.x),
            self.v.y.sat_add(dv.y),
            self.v.z.sat_add(dv.z),
        )
    }

    /// The velocity in pitch per step after `s` steps: `u + 2h·s`.
    #[inline]
    pub(crate) fn u_at(&self, s: S) -> Vec3<S> {
        self.u + (self.h + self.h).scale(s)
    }
}

/// `s²` as [`Segment::pos_at`] bends by it (rounded away from zero), for
/// [`along`].
#[inline]
pub(crate) fn bend_of<S: Scalar>(s: S) -> S {
    up(s, s)
}

/// One axis of [`Segment::pos_at`], bit for bit: from `p` at `u` per step bending
/// with `h`, after `s` steps (`s2`: [`bend_of`]`(s)`, unused for a whole step).
#[inline]
pub(crate) fn along<S: Scalar>(p: S, u: S, h: S, s: S, s2: S) -> S {
    if s == S::ONE {
        p + (u + h)
    } else {
        p + (u.times(s) + up(h, s2))
    }
}

/// `x·y` for `y ≥ 0`, rounded away from zero (fixed point; floating point rounds).
#[inline]
fn up<S: Scalar>(x: S, y: S) -> S {
    if x > S::ZERO {
        -((-x).times(y))
    } else {
        x.times(y)
    }
}

/// The first `σ ≥ 0` at which a gap closing as `gap − w·σ − β·σ²` reaches zero
/// (`w`: approach speed, `β`: half the approach acceleration; `gap ≥ 0`), or `None`
/// when it never does. The root is taken in the form that does not cancel:
/// `2·gap / (w + √(w² + 4β·gap))` when approaching, `(√… − w) / 2β` when receding
/// but pulled back.
///
/// The root does not change when all three are scaled by the same factor, so they
/// are first scaled by a power of two ([`normal_shift`]) that puts the largest near
/// ½: the squares then keep every bit, even for a slow marble in the 16-bit format.
#[inline]
pub(crate) fn first_root<S: Scalar>(gap: S, w: S, beta: S) -> Option<S> {
    if w <= S::ZERO && beta <= S::ZERO {
        // Not closing and not pulled in: never, without the square root that
        // the last branch below came to after it.
        return None;
    }
    let gap = gap.max(S::ZERO);
    if beta == S::ZERO {
        return if w > S::ZERO { Some(gap.div(w)) } else { None };
    }
    let m = normal_shift(gap.max(w.abs()).max(beta.abs()));
    let (gap, w, beta) = (gap.shl(m), w.shl(m), beta.shl(m));
    let disc = w.times(w) + beta.times(gap).shl(2);
    if disc < S::ZERO {
        return None;
    }
    let sq = disc.sqrt_fine();
    if w > S::ZERO {
        Some((gap + gap).div(w + sq))
    } else if beta > S::ZERO {
        Some((sq - w).div(beta + beta))
    } else {
        None
    }
}

/// The power of two `m` that puts `big · 2^m` in `[¼, ½)` (none for values already
/// at least ¼; at most 2^30): exact scaling for the quadratics.
#[inline]
pub(crate) fn normal_shift<S: Scalar>(big: S) -> u32 {
    if big >= S::ONE.shr(2) {
        // Already at least ¼: no count of leading zeros (a library call on
        // the M0) to find it.
        return 0;
    }
    let e = big.ilog2();
    if e >= -2 {
        0
    } else {
        (-2 - e).min(30) as u32
    }
}

/// The normal speed (pitch/s) at the contact plane of a marble approaching at `w`
/// (pitch/step) with half its acceleration `beta` (pitch/step²) towards it, still
/// `d` away (pitch; negative: past it): `√(w² + 4β·d)` — the energy along the
/// normal — or zero when that is not positive. Scaled like [`first_root`].
pub(crate) fn impact_speed<S: Scalar>(w: S, beta: S, d: S, k: u32) -> S {
    let m = normal_shift(w.abs().max(beta.abs()).max(d.abs()));
    let (w, beta, d) = (w.shl(m), beta.shl(m), d.shl(m));
    let q = w.times(w) + beta.times(d).shl(2);
    if q <= S::ZERO {
        return S::ZERO;
    }
    // √q is the speed in pitch/step times 2^m.
    let r = q.sqrt_fine();
    if k >= m {
        r.shl(k - m)
    } else {
        r.shr(m - k)
    }
}

/// The answer of [`toi_box`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum Toi<S> {
    /// No contact within the interval.
    Miss,
    /// Touching after `at` steps and moving in (or pulled in): the contact there
    /// (`depth` within the tolerance of zero) and the offset `d` from the box's
    /// closest point to the centre (for the ghost-bump rule).
    Hit {
        /// When.
        at: S,
        /// Normal, depth, feature, plane.
        contact: Contact<S>,
        /// `centre − closest point of the box`.
        d: Vec3<S>,
    },
    /// The centre is inside the box, or deeper in the rounded box than the
    /// tolerance, after `at` steps (it started there).
    Inside {
        /// When.
        at: S,
    },
    /// Not touched before `at` steps: search again from there.
    Later(S),
}

/// The first contact, within `len` steps, of a marble of radius `r` flying `seg`
/// with the box `b`, by conservative advancement along separating planes (see the
/// module doc). Touching means within `tol` of the rounded box.
pub(crate) fn toi_box<S: Scalar>(seg: &Segment<S>, r: S, b: &Aabb<S>, len: S, tol: S) -> Toi<S> {
    let mut s = S::ZERO;
    for _ in 0..CA_STEPS {
        let c = if s == S::ZERO { seg.p } else { seg.pos_at(s) };
        let d = offset(c, b);
        let mut nonzero = 0;
        let mut axis = 0;
        for a in 0..3 {
            if d.axis(a) != S::ZERO {
                nonzero += 1;
                axis = a;
            }
        }
        let (n, dist, feature, plane) = match nonzero {
            0 => return Toi::Inside { at: s },
            1 => {
                let v = d.axis(axis);
                let up = v > S::ZERO;
                let plane = if up {
                    b.max.axis(axis)
                } else {
                    b.min.axis(axis)
                };
                (unit(axis, up), v.abs(), Feature::Face(axis as u8), plane)
            }
            _ => {
                let len2 = d.length_sq();
                let inv = len2.rsqrt_fine();
                if inv == S::ZERO {
                    return Toi::Inside { at: s };
                }
                let dist = len2.times(inv);
                // Deep inside at the start (the test below, before the normal
                // and its two dot products that it does not need: nine products
                // for every round of a pair pressed together, drop-onto-marble).
                if s == S::ZERO && dist - r < -tol {
                    return Toi::Inside { at: s };
                }
                (d.scale(inv), dist, Feature::Edge, S::ZERO)
            }
        };
        let gap = dist - r;
        // At the start the velocity is the flight's own (no `2h·0` to add: three
        // products fewer for every tile a search asks).
        let (w, beta) = if let Feature::Face(_) = feature {
            // A face's normal is a unit axis: the dot products are that axis's
            // velocity and pull, negated towards the face (bit for bit: `x·±1`
            // and `x·0` are exact), one product where the vectors take nine.
            let (u, h) = (seg.u.axis(axis), seg.h.axis(axis));
            let u = if s == S::ZERO {
                u
            } else {
                u + (h + h).times(s)
            };
            if n.axis(axis) > S::ZERO {
                (-u, -h)
            } else {
                (u, h)
            }
        } else {
            let u = if s == S::ZERO { seg.u } else { seg.u_at(s) };
            (-n.dot(u), -n.dot(seg.h))
        };
        let contact = || Toi::Hit {
            at: s,
            contact: Contact {
                normal: n,
                depth: r - dist,
                feature,
                plane,
            },
            d,
        };
        if gap <= tol {
            if s == S::ZERO && gap < -tol {
                return Toi::Inside { at: s };
            }
            // Arrived here by an advance that rounding carried a little past the
            // surface: still the touch (the caller puts it back on the surface).
            if w > S::ZERO || (w == S::ZERO && beta > S::ZERO) || s > S::ZERO {
                return contact();
            }
        }
        if open_through(gap, w, beta, len - s, tol) {
            return Toi::Miss;
        }
        let Some(step) = first_root(gap, w, beta) else {
            return Toi::Miss;
        };
        if step > len - s {
            return Toi::Miss;
        }
        if step == S::ZERO {
            // Closing with no time left to close in: the contact, now.
            return contact();
        }
        s += step;
    }
    Toi::Later(s)
}

/// Whether a gap closing as `gap − w·σ − β·σ²` with `w > 0` is still open by
/// more than `tol` after `rest ≤ 1` steps, judged without a root: in `σ ≤ 1`
/// steps it closes by at most `(w + max(β, 0))·σ`. Open there, it is open all
/// through, its first root lies past `rest` by more than the rounding of
/// [`first_root`]'s (which for `w > 0` is never more than an LSB short of the
/// exact root, or none: its square and products round down, its quotient
/// towards zero), and `first_root` would say so at the cost of a square root
/// and a quotient: the same miss.
#[inline]
fn open_through<S: Scalar>(gap: S, w: S, beta: S, rest: S, tol: S) -> bool {
    w > S::ZERO && rest <= S::ONE && gap - (w + beta.max(S::ZERO)).times(rest) > tol
}

/// The first time within `len` steps at which the centre is inside the box on the
/// axes of `axes` (`[lo, hi]` each), as a lower bound that is exact when it
/// converges: `(time, converged)`, or `None` when it never gets there. Used for
/// the end of a held face's support (the centre entering a column whose tile is
/// missing).
pub fn entry<S: Scalar>(
    seg: &Segment<S>,
    lo: Vec3<S>,
    hi: Vec3<S>,
    axes: [bool; 3],
    len: S,
) -> Option<(S, bool)> {
    let mut s = S::ZERO;
    for _ in 0..4 {
        let c = if s == S::ZERO { seg.p } else { seg.pos_at(s) };
        let u = seg.u_at(s);
        let mut next = s;
        let mut inside = true;
        for (a, on) in axes.iter().enumerate() {
            if !on {
                continue;
            }
            let (x, w, h) = (c.axis(a), u.axis(a), seg.h.axis(a));
            let step = if x < lo.axis(a) {
                first_root(lo.axis(a) - x, w, h)
            } else if x > hi.axis(a) {
                first_root(x - hi.axis(a), -w, -h)
            } else {
                continue;
            };
            inside = false;
            match step {
                Some(st) if st <= len - s => next = next.max(s + st),
                _ => return None,
            }
        }
        if inside {
            return Some((s, true));
        }
        s = next;
    }
    Some((s, false))
}

#[cfg(test)]
mod tests {
    use super::*;
    use fixed::types::I8F24;
    use rand_core::{Rng, SeedableRng};
    use rand_xorshift::XorShiftRng;

    type S = I8F24;

    fn f(x: f64) -> S {
        S::from_f64(x)
    }

    #[test]
    fn first_root_matches_the_quadratic() {
        // gap − wσ − βσ² = 0 for a few shapes, against f64.
        for (gap, w, beta) in [
            (0.1, 0.5, 0.0),
            (0.1, 0.5, 0.2),
            (0.1, 0.5, -0.2),
            (0.1, -0.1, 0.3),
            (0.0, -0.1, 0.3),
            (0.3, 0.2, -0.5),
        ] {
            let want = {
                let disc = w * w + 4.0 * beta * gap;
                if beta == 0.0 {
                    (w > 0.0).then(|| gap / w)
                } else if disc < 0.0 {
                    None
                } else if w > 0.0 {
                    Some(2.0 * gap / (w + disc.sqrt()))
                } else if beta > 0.0 {
                    Some((disc.sqrt() - w) / (2.0 * beta))
                } else {
                    None
                }
            };
            let got = first_root(f(gap), f(w), f(beta)).map(|x| x.to_f64());
            match (want, got) {
                (Some(a), Some(b)) => assert!((a - b).abs() < 1e-5, "{gap} {w} {beta}: {a} {b}"),
                (None, None) => {}
                _ => panic!("{gap} {w} {beta}: {want:?} vs {got:?}"),
            }
        }
        // Decelerating short of the gap: never.
        assert_eq!(first_root(f(0.3), f(0.2), f(-0.5)), None);
    }

    /// Where [`open_through`] says the gap stays open, [`first_root`]'s root
    /// lies past the interval or there is none (so `toi_box` missed there
    /// before the shortcut too), in I8F24 and I16F16: random closings, pulls
    /// either way, gaps and intervals, many near the boundary; and the
    /// shortcut is taken for many of them.
    #[test]
    fn open_through_is_first_root_past_the_interval() {
        fn check<T: Scalar>(tol: T, taken: &mut u32, rng: &mut XorShiftRng) {
            let mut next = || (rng.next_u64() >> 11) as f64 / (1u64 << 53) as f64;
            for _ in 0..100_000 {
                let scale = [1.0, 1e-2, 1e-4][(next() * 3.0) as usize];
                let w = T::from_f64(next() * scale);
                let beta = T::from_f64((next() - 0.4) * scale);
                let rest = T::from_f64(next());
                // A gap around what closes in `rest`, often just past it.
                let closes = w.times(rest) + beta.times(rest.times(rest));
                let gap = closes + T::from_f64((next() - 0.3) * scale * 0.1);
                if gap <= T::ZERO || !open_through(gap, w, beta, rest, tol) {
                    continue;
                }
                *taken += 1;
                let step = first_root(gap, w, beta);
                assert!(
                    step.is_none_or(|st| st > rest),
                    "{gap:?} {w:?} {beta:?} over {rest:?}: {step:?}"
                );
            }
        }
        let (mut taken, mut rng) = (0, XorShiftRng::seed_from_u64(0x9e37_79b9_7f4a_7c15));
        check(S::from_f64(0.25 / 16384.0), &mut taken, &mut rng);
        assert!(taken > 20_000, "I8F24: only {taken}");
        taken = 0;
        let lsb = fixed::types::I16F16::from_bits(1);
        check(lsb + lsb + lsb + lsb, &mut taken, &mut rng);
        assert!(taken > 10_000, "I16F16: only {taken}");
    }

    #[test]
    fn a_face_is_hit_at_the_exact_time() {
        // Towards a wall at x = 1 (box [1, 2]), r = 0.25, from x = 0.3 at 0.5
        // pitch/step with h = 0.1: 0.45 = 0.5σ + 0.1σ².
        let seg = Segment {
            p: Vec3::new(f(0.3), f(0.5), f(0.5)),
            v: Vec3::ZERO,
            u: Vec3::new(f(0.5), S::ZERO, S::ZERO),
            dv: Vec3::ZERO,
            h: Vec3::new(f(0.1), S::ZERO, S::ZERO),
        };
        let b = Aabb {
            min: Vec3::new(f(1.0), f(0.0), f(0.0)),
            max: Vec3::new(f(2.0), f(1.0), f(1.0)),
        };
        let tol = f(1e-5);
        let Toi::Hit { at, contact, .. } = toi_box(&seg, f(0.25), &b, S::ONE, tol) else {
            panic!("no hit");
        };
        let want = (-0.5 + (0.25f64 + 0.4 * 0.45).sqrt()) / 0.2;
        assert!((at.to_f64() - want).abs() < 1e-5, "{at:?} vs {want}");
        assert_eq!(contact.feature, Feature::Face(0));
        assert_eq!(contact.normal, Vec3::new(-S::ONE, S::ZERO, S::ZERO));
        // Sideways past it: no contact.
        let past = Segment {
            u: Vec3::new(S::ZERO, S::ZERO, f(0.5)),
            h: Vec3::ZERO,
            ..seg
        };
        assert_eq!(toi_box(&past, f(0.25), &b, S::ONE, tol), Toi::Miss);
    }

    #[test]
    fn a_corner_is_hit_where_the_circle_is() {
        // Moving along x at z = 0.1 above a box's corner edge at (1, ·, 0): the
        // centre meets the rounded corner (radius 0.25) at x = 1 − √(0.25² − 0.1²).
        let seg = Segment {
            p: Vec3::new(f(0.0), f(0.5), f(0.1)),
            v: Vec3::ZERO,
            u: Vec3::new(f(1.0), S::ZERO, S::ZERO),
            dv: Vec3::ZERO,
            h: Vec3::ZERO,
        };
        let b = Aabb {
            min: Vec3::new(f(1.0), f(0.0), f(-1.0)),
            max: Vec3::new(f(2.0), f(1.0), f(0.0)),
        };
        let Toi::Hit { at, contact, .. } = toi_box(&seg, f(0.25), &b, S::ONE, f(1e-5)) else {
            panic!("no hit");
        };
        let want = 1.0 - (0.0625f64 - 0.01).sqrt();
        assert!((at.to_f64() - want).abs() < 1e-4, "{at:?} vs {want}");
        assert_eq!(contact.feature, Feature::Edge);
        // Passing the corner at z = 0.26: no contact.
        let wide = Segment {
            p: Vec3::new(f(0.0), f(0.5), f(0.26)),
            ..seg
        };
        assert!(matches!(
            toi_box(&wide, f(0.25), &b, S::ONE, f(1e-5)),
            Toi::Miss | Toi::Later(_)
        ));
    }
}
