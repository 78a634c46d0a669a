//! The time of impact of two marbles flying together (`together.rs`): out of
//! reach without a product (`beyond`), out of reach on one axis (`reach`), or
//! the first contact of a sphere of radius 2r about a point in their relative
//! motion (`toi_box`).

use super::{
    along, bend_of, max_abs, quarter, swept_axis, toi_box, Aabb, Flight, Scalar, Segment, Toi, Vec3,
};

/// The first contact of marbles flying `fa` and `fb`, from `t0` (steps, at or
/// after both flights' starts) over `horizon`: in their relative motion, a
/// sphere of radius `r2` about a point (`toi_box`), or `None` when the pair is
/// out of reach over that horizon. Out of line and with the kind of world out
/// of its type: the timeline has four copies (the two kinds of world, two
/// marbles or more), this code one (the v1's flash).
#[inline(never)]
pub(super) fn pair_toi<S: Scalar>(
    fa: &Flight<S>,
    fb: &Flight<S>,
    t0: S,
    horizon: S,
    r2: S,
    tol: S,
) -> Option<Toi<S>> {
    let near = r2 + tol;
    // Nearly half of four-shaken's pair tests end here, three in five of those
    // the swept test finds out of reach, which took them 31 products each.
    if far_apart(fa, fb, r2, tol) {
        return None;
    }
    let rel = reach(fa, fb, t0, horizon, near)?;
    let point = Aabb {
        min: Vec3::ZERO,
        max: Vec3::ZERO,
    };
    Some(toi_box(&rel, r2, &point, horizon, tol))
}

/// Whether the marbles flying `fa` and `fb` are out of each other's reach over
/// the whole step, wherever on their segments they are (`pair_toi`'s first
/// answer).
#[inline]
pub(super) fn far_apart<S: Scalar>(fa: &Flight<S>, fb: &Flight<S>, r2: S, tol: S) -> bool {
    beyond(&fa.seg, &fb.seg, r2 + tol + r2.shr(4))
}

/// Whether two flights are further apart on some axis than `far` and all that
/// both can travel in a whole step: `|u| + |h|` each (each segment starts within
/// the step, and a pair's horizon ends no later than the step), `|h|` more
/// for the swept box's bulge. With `far` above [`reach`]'s by a margin
/// far above the rounding of its positions (`r/8`, against a few LSB), such
/// a pair is out of its reach too: the same answer, without a product.
#[inline]
fn beyond<S: Scalar>(ga: &Segment<S>, gb: &Segment<S>, far: S) -> bool {
    let apart = |d: S, ua: S, ha: S, ub: S, hb: S| {
        let h = ha.abs() + hb.abs();
        d.abs() > far + ua.abs() + ub.abs() + h + h
    };
    let d = gb.p - ga.p;
    apart(d.x, ga.u.x, ga.h.x, gb.u.x, gb.h.x)
        || apart(d.z, ga.u.z, ga.h.z, gb.u.z, gb.h.z)
        || apart(d.y, ga.u.y, ga.h.y, gb.u.y, gb.h.y)
}

/// The pair's relative motion from `t0` (`fb`'s less `fa`'s, both where their
/// flights are then), or `None` where it does not come within `near` on every
/// axis over `horizon`: out of reach, no touch, and no square of a far
/// separation (I8F24's |d|² leaves its range past 11.3 pitch; wrapped, a pair
/// 16 pitches apart read as touching). Within reach every axis is under 2r +
/// tol plus a step's relative travel (2 pitch at 127 pitch/s): squares under
/// 48. Axis by axis (the swept box's, `swept`), the axis the
/// the flights start furthest apart on first. More than half of four-shaken's
/// pair tests past [`beyond`] end out of reach, most on that axis, which takes
/// 13 products at most where the three took 31.
#[inline]
fn reach<S: Scalar>(
    fa: &Flight<S>,
    fb: &Flight<S>,
    t0: S,
    horizon: S,
    near: S,
) -> Option<Segment<S>> {
    let (ga, gb) = (&fa.seg, &fb.seg);
    let (sa, sb) = (t0 - fa.t, t0 - fb.t);
    let d = gb.p - ga.p;
    if sa == S::ZERO && sb == S::ZERO && max_abs(d) <= near {
        // Both where their flights start, within reach there (a pair pressed
        // together, every round): the motion as it stands, no axis to sweep.
        return Some(Segment {
            p: d,
            v: Vec3::ZERO,
            u: gb.u - ga.u,
            dv: Vec3::ZERO,
            h: gb.h - ga.h,
        });
    }
    let bend = |s: S| {
        if s == S::ZERO || s == S::ONE {
            S::ZERO
        } else {
            bend_of(s)
        }
    };
    let (qa, qb) = (bend(sa), bend(sb));
    // Where a flight starts: no closed form to evaluate.
    let at = |g: &Segment<S>, axis: usize, s: S, q: S| {
        let (p, u, h) = (g.p.axis(axis), g.u.axis(axis), g.h.axis(axis));
        if s == S::ZERO {
            (p, u)
        } else {
            (along(p, u, h, s, q), u + (h + h).times(s))
        }
    };
    let mut rel = Segment::still(Vec3::ZERO);
    let mut ends = None;
    // `apart_axis`'s bound holds over a horizon within a step.
    let short = horizon >= S::ZERO && horizon <= S::ONE;
    let first = far_axis(d);
    for k in 0..3 {
        let axis = if first + k >= 3 {
            first + k - 3
        } else {
            first + k
        };
        let ((pa, ua), (pb, ub)) = (at(ga, axis, sa, qa), at(gb, axis, sb, qb));
        let (p, u, h) = (pb - pa, ub - ua, gb.h.axis(axis) - ga.h.axis(axis));
        // The swept interval holds the start: within `near` there, the axis is
        // within reach without its end.
        if p.abs() > near {
            if short && apart_axis(p, u, h, near) {
                return None;
            }
            let (qh, quarter) = *ends.get_or_insert_with(|| (bend(horizon), quarter(horizon)));
            let (lo, hi) = swept_axis(p, along(p, u, h, horizon, qh), h, quarter);
            if lo > near || hi < -near {
                return None;
            }
        }
        rel.p.set_axis(axis, p);
        rel.u.set_axis(axis, u);
        rel.h.set_axis(axis, h);
    }
    Some(rel)
}

/// Whether one axis of a pair's relative motion (`p` at the start, beyond
/// `near`, `u` a step, bending with `h`) stays beyond `near` over a horizon
/// within a step, by a bound without a product: then [`reach`]'s swept
/// interval on that axis is beyond it too, the same answer without the
/// horizon's four products and the bulge's. Over `σ ≤ 1` step the path's end
/// is `p + u·σ + h·σ²` with each term rounded no further from zero than
/// `u` and `h` themselves (products of a factor in `[0, 1]`), and the swept
/// interval widens that by the bulge (`|h|·σ²/4`, under `|h|`) and one LSB:
/// so for `p > 0` its low end is at least `p + min(u, 0) − |h| − lsb`, and
/// the mirror for `p < 0`. `near/4096` more covers the floating-point formats'
/// rounding; the ranges asked (under 8 pitch a step, under 64 pitch apart)
/// keep every sum here and in the swept interval from wrapping. Four shaken
/// marbles, each beside two others: most of their pair tests past
/// [`beyond`] are a pair moving apart on the axis they touch along, out of
/// reach at once whatever the horizon.
#[inline]
fn apart_axis<S: Scalar>(p: S, u: S, h: S, near: S) -> bool {
    let (step, far) = (S::from_int(8), S::from_int(64));
    let within = |v: S, top: S| v < top && v > -top;
    if !(within(u, step) && within(h, step) && within(p, far)) {
        return false;
    }
    let lsb = S::lsb();
    let slack = h.abs() + lsb + near.shr(12);
    if p > S::ZERO {
        p + u.min(S::ZERO) - slack > near
    } else {
        p + u.max(S::ZERO) + slack < -near
    }
}

/// The axis of `d`'s largest magnitude (the first of equals).
#[inline]
fn far_axis<S: Scalar>(d: Vec3<S>) -> usize {
    let (x, y, z) = (d.x.abs(), d.y.abs(), d.z.abs());
    if x >= y && x >= z {
        0
    } else if y >= z {
        1
    } else {
        2
    }
}

#[cfg(test)]
mod tests {
    use super::super::swept;
    use super::*;
    use fixed::types::I8F24;
    use rand_core::{Rng, SeedableRng};
    use rand_xorshift::XorShiftRng;

    type S = I8F24;

    /// The relative motion as it was formed for all three axes at once
    /// (`pos_at`, `u_at`): [`reach`]'s reference.
    fn relative<S: Scalar>(fa: &Flight<S>, fb: &Flight<S>, t0: S) -> Segment<S> {
        let at = |f: &Flight<S>| {
            let g = &f.seg;
            let s = t0 - f.t;
            if s == S::ZERO {
                return (g.p, g.u, g.h);
            }
            (g.pos_at(s), g.u_at(s), g.h)
        };
        let ((pa, ua, ha), (pb, ub, hb)) = (at(fa), at(fb));
        Segment {
            p: pb - pa,
            v: Vec3::ZERO,
            u: ub - ua,
            dv: Vec3::ZERO,
            h: hb - ha,
        }
    }

    /// [`beyond`] and, axis by axis, [`apart_axis`] never say out of reach
    /// where the swept box reaches, and [`reach`] is the swept box's answer with the relative motion formed for
    /// all axes at once, bit for bit, in the firmware's format: random pairs of
    /// flights (positions a few pitches apart, velocities and pulls up to the
    /// step's bounds, start times and horizons across the step); both
    /// shortcuts are taken for many of them, the bound on each axis for many,
    /// and many pairs are out of reach
    /// on one axis only, on each axis.
    #[test]
    fn beyond_reach_is_out_of_the_swept_reach() {
        let mut rng = XorShiftRng::seed_from_u64(0x853c_49e6_748f_ea9b);
        let mut next = |scale: f64| {
            S::from_f64(((rng.next_u64() >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0) * scale)
        };
        let (r2, tol) = (S::from_f64(0.5), S::from_f64(0.5 / 16384.0));
        let near = r2 + tol;
        let (mut beyond_count, mut started_near) = (0, 0);
        let mut one_axis = [0u32; 3];
        let mut quick = [0u32; 3];
        let mut both_start_near = 0;
        for round in 0..200_000 {
            let mut flight = || {
                let mut f = Flight::START;
                f.t = next(1.0).abs();
                f.seg = Segment {
                    p: Vec3::new(next(3.0), next(1.0), next(3.0)),
                    v: Vec3::ZERO,
                    u: Vec3::new(next(1.0), next(1.0), next(1.0)),
                    dv: Vec3::ZERO,
                    h: Vec3::new(next(0.5), next(0.5), next(0.5)),
                };
                f
            };
            let (fa, mut fb) = (flight(), flight());
            if round % 4 == 0 {
                // Both at their flights' starts (a pair that has just flown a
                // slice together).
                fb.t = fa.t;
            }
            let (ta, tb) = (fa.t, fb.t);
            let t0 = Scalar::max(ta, tb);
            let horizon = (S::ONE - t0).times(next(1.0).abs());
            let rel = relative(&fa, &fb, t0);
            // The swept box itself, without `reach`'s shortcuts for a start
            // already within reach.
            let path = swept(rel.p, rel.pos_at(horizon), rel.h, horizon);
            let reach = path.min.x <= near
                && path.max.x >= -near
                && path.min.y <= near
                && path.max.y >= -near
                && path.min.z <= near
                && path.max.z >= -near;
            assert_eq!(
                super::reach(&fa, &fb, t0, horizon, near),
                reach.then_some(rel),
                "{fa:?} {fb:?} from {t0:?} over {horizon:?}"
            );
            let out = [
                path.min.x > near || path.max.x < -near,
                path.min.y > near || path.max.y < -near,
                path.min.z > near || path.max.z < -near,
            ];
            if out.iter().filter(|&&o| o).count() == 1 {
                one_axis[out.iter().position(|&o| o).unwrap_or(0)] += 1;
            }
            for (axis, &o) in out.iter().enumerate() {
                let (p, u, h) = (rel.p.axis(axis), rel.u.axis(axis), rel.h.axis(axis));
                if p.abs() > near && apart_axis(p, u, h, near) {
                    quick[axis] += 1;
                    assert!(o, "{fa:?} {fb:?} from {t0:?} over {horizon:?}, axis {axis}");
                }
            }
            if max_abs(rel.p) <= near {
                started_near += 1;
                if ta == tb {
                    both_start_near += 1;
                }
            }
            if beyond(&fa.seg, &fb.seg, near + r2.shr(4)) {
                beyond_count += 1;
                assert!(!reach, "{fa:?} {fb:?} from {t0:?} over {horizon:?}");
            }
        }
        assert!(
            beyond_count > 20_000,
            "only {beyond_count} pairs beyond reach"
        );
        assert!(
            started_near > 1_000,
            "only {started_near} pairs starting near"
        );
        assert!(
            both_start_near > 300,
            "only {both_start_near} pairs near at both flights' starts"
        );
        assert!(
            one_axis.iter().all(|&n| n > 1_000),
            "out of reach on one axis only: {one_axis:?}"
        );
        assert!(
            quick.iter().all(|&n| n > 1_000),
            "apart by the bound without a product: {quick:?}"
        );
    }
}
