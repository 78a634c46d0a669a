//! Collision response: eq. 1, and what happens in the step in which a contact starts.
//!
//! Eq. 1, `v_m' = v_m − (1 + e)((v_m − v_b)·n) n`, is the seed's law for a bounce off
//! a board moving at `v_b`. The seed does not say *when* in a step the bounce
//! happens, nor what to do with a marble that merely rests on a surface. Here:
//!
//! * The normal motion in the step is a parabola (constant acceleration), so the
//!   impact time and the approach speed at impact are solved exactly from the state
//!   at the end of the step: with approach speed `w`, acceleration into the surface
//!   `b` and depth `δ`, the speed at impact is `w_c = √(w² − 2bδ)` (energy along the
//!   normal) and the time since impact `τ = 2δ/(w + w_c)`. Eq. 1 is applied at that
//!   instant, and the rest of the step is flown exactly. For `e = 1` this conserves
//!   energy to the last bit of rounding, at any step size.
//! * **Restitution threshold.** When `w_c` is below the threshold the impact is a
//!   *contact*: the marble is put on the surface with no normal velocity (resting or
//!   sliding). No bounce, no jitter, no sinking, and no root is taken (the threshold
//!   test compares squares): a marble resting against a wall costs a few adds a step.
//! * Positional correction only ever moves the marble along the normal back to where
//!   the exact motion puts it; a push-out that would lift it against the
//!   acceleration is paid for from its normal speed, so it never injects energy.
//!
//! All quantities here are in the solver's time unit `T = 1/32 s` (pitch/T,
//! pitch/T²): at the 64 pitch/s speed cap a speed is at most 2 pitch/T, so its square
//! fits the narrowest fixed format, while the energies of slow bounces keep ~10⁵ LSB
//! of resolution (in per-step units at 1024 steps/s they had ~500).

use super::super::scalar::Scalar;
use super::super::vec::Vec3;

/// Eq. 1: the marble's velocity after bouncing off a board moving at `v_b`.
#[inline]
pub fn restitution<S: Scalar>(v_m: Vec3<S>, v_b: Vec3<S>, n: Vec3<S>, e: S) -> Vec3<S> {
    let vn = n.dot(v_m - v_b);
    v_m - n.scale((S::ONE + e).times(vn))
}

/// What a contact turned out to be.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Outcome {
    /// Already moving away: only pushed out.
    Separating,
    /// Slower than the restitution threshold: put on the surface, normal speed zero.
    Contact,
    /// A bounce (eq. 1 at the instant of impact).
    Collision,
}

/// `log2` of the solver's time unit: `T = 2^-5 s`.
pub(crate) const T_LOG2: u32 = 5;

/// One contact to resolve, in solver units (pitch, `T`).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Impact<S> {
    /// Unit normal out of the board, towards the marble.
    pub n: Vec3<S>,
    /// Penetration depth at the end of the step (pitch, `> 0`).
    pub depth: S,
    /// Marble velocity (pitch/T).
    pub v: Vec3<S>,
    /// Board velocity at the contact (pitch/T), eq. 1's `v_b`: the world passes
    /// zero, as it works in the board's frame (`world::contact`'s doc).
    pub(crate) v_board: Vec3<S>,
    /// Acceleration over the step (pitch/T²).
    pub(crate) acc: Vec3<S>,
    /// The step's length in `T` (the latest the impact can have been).
    pub dt: S,
    /// `n` is this axis's unit vector (towards + when `true`): a face's normal
    /// ([`normal_part`]).
    pub(crate) face: Option<(usize, bool)>,
}

/// `v·n` for a unit normal `n` that is, when `face` says so, an axis's unit
/// vector: there that component of `v` (±), without the three products, where
/// the format makes it the same bits ([`Scalar::EXACT_UNIT`]). A face's
/// contact takes five such products and five scales by its normal, each a
/// call on the Cortex-M0 (no 32 × 32 → 64 multiply), and a marble pressed on
/// another takes two face contacts a pair slice.
#[inline]
pub(crate) fn normal_part<S: Scalar>(v: Vec3<S>, n: Vec3<S>, face: Option<(usize, bool)>) -> S {
    match face {
        Some((axis, up)) if S::EXACT_UNIT => {
            let c = v.axis(axis);
            if up {
                c
            } else {
                -c
            }
        }
        // The normal first: an edge's zero component is then the Cortex-M0
        // product's first operand, which it answers at once.
        _ => n.dot(v),
    }
}

/// `n·k` for a unit normal `n`, by [`normal_part`]'s rule: on a face's axis,
/// `±k` there and zero elsewhere, the same bits without the products.
#[inline]
pub(crate) fn along_normal<S: Scalar>(n: Vec3<S>, k: S, face: Option<(usize, bool)>) -> Vec3<S> {
    match face {
        Some((axis, up)) if S::EXACT_UNIT => {
            let mut v = Vec3::ZERO;
            v.set_axis(axis, if up { k } else { -k });
            v
        }
        _ => n.scale(k),
    }
}

/// How to move the marble: along `n` by `push` (pitch), and its normal velocity
/// relative to the board becomes `vn` (pitch/T).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Resolution<S> {
    /// Distance to move along the normal (`depth + lift`).
    pub push: S,
    /// How far off the surface the marble ends (0 unless it bounced).
    pub lift: S,
    /// Energy per unit mass (pitch²/T²) the push-out costs beyond what the normal
    /// speed could pay: the caller takes it from the tangential speed.
    pub(crate) deficit: S,
    /// New normal velocity relative to the board (pitch/T).
    pub vn: S,
    /// A bounce's normal speed at the instant of impact, relative to the board
    /// (pitch/T; zero for the other outcomes): what the game's click follows.
    pub impact: S,
    /// Which case applied.
    pub outcome: Outcome,
}

/// Resolves one contact with restitution `e` and restitution threshold `threshold`
/// (pitch/T).
pub(crate) fn resolve<S: Scalar>(c: &Impact<S>, e: S, threshold: S) -> Resolution<S> {
    let two = S::from_int(2);
    let vn = normal_part(c.v - c.v_board, c.n, c.face);
    let w = -vn;
    let b = -normal_part(c.acc, c.n, c.face);
    let delta = c.depth;
    if w <= S::ZERO {
        // Moving away but overlapping (an edge came into reach sideways). Lifting it
        // by δ against b costs b·δ of energy: take it from the normal speed, and what
        // that cannot pay from the tangential speed (the caller's `deficit`).
        let mut out = vn;
        let mut deficit = S::ZERO;
        if b > S::ZERO {
            let e2 = vn.times(vn) - two.times(b).times(delta);
            if e2 > S::ZERO {
                out = e2.sqrt();
            } else {
                out = S::ZERO;
                deficit = (-e2).half();
            }
        }
        return Resolution {
            push: delta,
            lift: S::ZERO,
            vn: out,
            impact: S::ZERO,
            outcome: Outcome::Separating,
            deficit,
        };
    }
    let wc2 = w.times(w) - two.times(b).times(delta);
    if wc2 <= threshold.times(threshold) {
        // Put on the surface with no normal speed. When the normal energy ½w² does
        // not cover lifting it by δ against b (a marble grazing an edge sideways),
        // the rest is the caller's to take from the tangential speed.
        // The unpaid part of the lift, `δ − w²/2b`: a few ULPs of it are the
        // integrator's own rounding of ½·a·dt² away from zero (already paid for in
        // free flight), not a deficit.
        let mut deficit = S::ZERO;
        if wc2 < S::ZERO && b > S::ZERO {
            let unpaid = delta - w.times(w).div(b + b);
            if unpaid > (delta - delta.next_down()).times(S::from_int(8)) {
                deficit = b.times(unpaid);
            }
        }
        return Resolution {
            push: delta,
            lift: S::ZERO,
            vn: S::ZERO,
            impact: S::ZERO,
            outcome: Outcome::Contact,
            deficit,
        };
    }
    let wc = wc2.sqrt();
    let tau = two.times(delta).div(w + wc).min(c.dt);
    // The velocity at impact: tangential part as now, normal part −w_c.
    let v_c = c.v + c.n.scale(w - wc);
    let out = (restitution(v_c, c.v_board, c.n, e) - c.v_board).dot(c.n);
    let u = out.times(tau) - b.times(tau).times(tau.half());
    if u <= S::ZERO {
        return Resolution {
            push: delta,
            lift: S::ZERO,
            vn: S::ZERO,
            impact: S::ZERO,
            outcome: Outcome::Contact,
            deficit: S::ZERO,
        };
    }
    // Rounding must not add energy: the normal energy after (½vn² + b·u) may not
    // exceed the energy before (½w² − b·δ, the state at the end of the step).
    let mut vn = out - b.times(tau);
    let before = w.times(w.half()) - b.times(delta);
    if vn.times(vn.half()) + b.times(u) > before {
        let room = before - b.times(u);
        let mut mag = if room > S::ZERO {
            (room + room).sqrt()
        } else {
            S::ZERO
        };
        // The root rounds, and an approximate one (micromath) may overshoot: step
        // down an ULP at a time, then by 1/64 at a time.
        let mut tries = 0;
        while mag > S::ZERO && mag.times(mag.half()) + b.times(u) > before && tries < 16 {
            mag = if tries < 4 {
                mag.next_down()
            } else {
                mag - mag.shr(6)
            }
            .max(S::ZERO);
            tries += 1;
        }
        if tries == 16 {
            mag = S::ZERO;
        }
        vn = if vn < S::ZERO { -mag } else { mag };
    }
    Resolution {
        push: delta + u,
        lift: u,
        vn,
        impact: wc,
        outcome: Outcome::Collision,
        deficit: S::ZERO,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use fixed::types::{I16F16, I8F24};
    use rand_core::{Rng, SeedableRng};
    use rand_xorshift::XorShiftRng;

    /// On a face's normal (each axis, both ways) [`normal_part`] and
    /// [`along_normal`] are the dot product and the scale bit for bit in the
    /// fixed-point formats, over random vectors and the range's ends, and are
    /// them outright for any other normal.
    #[test]
    fn a_face_normal_takes_its_component_bit_for_bit() {
        fn check<T: Scalar>(bits: impl Fn(i32) -> T, rng: &mut XorShiftRng) -> u32 {
            let top = bits(i32::MAX);
            let ends = [T::ZERO, top, -top, bits(1), bits(-1), T::ONE, -T::ONE];
            let mut checked = 0;
            for round in 0..20_000 {
                let mut pick = || {
                    let r = rng.next_u32() as i32;
                    match round % 4 {
                        0 => ends[(r as u32 % ends.len() as u32) as usize],
                        _ => bits(r >> 1),
                    }
                };
                let (v, k) = (Vec3::new(pick(), pick(), pick()), pick());
                for axis in 0..3 {
                    for up in [false, true] {
                        let mut n = Vec3::ZERO;
                        n.set_axis(axis, if up { T::ONE } else { -T::ONE });
                        let face = Some((axis, up));
                        assert_eq!(normal_part(v, n, face), v.dot(n), "{v:?} {n:?}");
                        assert_eq!(along_normal(n, k, face), n.scale(k), "{n:?} {k:?}");
                        checked += 1;
                    }
                }
                let slanted = Vec3::new(T::ONE.half(), -T::ONE.half(), T::ZERO);
                assert_eq!(normal_part(v, slanted, None), v.dot(slanted));
                assert_eq!(along_normal(slanted, k, None), slanted.scale(k));
            }
            checked
        }
        let mut rng = XorShiftRng::seed_from_u64(0x2545_f491_4f6c_dd1d);
        const { assert!(I8F24::EXACT_UNIT && I16F16::EXACT_UNIT && !f32::EXACT_UNIT) };
        assert_eq!(check(I8F24::from_bits, &mut rng), 120_000);
        assert_eq!(check(I16F16::from_bits, &mut rng), 120_000);
    }
}
