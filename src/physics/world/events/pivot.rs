//! Rolling around an edge: a slice that pivots on it instead of sinking into it.
//!
//! A marble pulled slowly over an edge or a corner — off the rim of a hole, round
//! the end of a wall — moves on a sphere of radius `r` about the edge's nearest
//! point: not a parabola, so it was flown in plain slices, each short enough that
//! the pull sinks it at most `2^-12·r` into the edge before the passes push it
//! out. At a 12 mm pitch and 1 g that is 32 slices a frame, each a search and a
//! set of passes: the worst frame of every level with holes (345 k instructions
//! on the Cortex-M4F, against about 2 k for an ordinary frame), long enough to
//! starve the sensor's task.
//!
//! A **pivot slice** drops instead the pull's part along the normal `n` from the
//! edge while the edge holds the marble — while the pull presses harder than the
//! turn needs, `−a·n > v_t²/r` (the normal force is positive; below it the
//! marble leaves the edge, as a real one does). The slice then flies the tangent
//! and cannot sink: the tangent leaves the sphere by `r·δθ²/2` for a turn `δθ`,
//! and at the slice's end the centre is put back on it, `r` (and a tolerance) from
//! the edge, with the velocity turned to the new tangent at no more than its speed
//! (the radial part dropped, `1 + x/2 − x²/8 ≤ √(1 + x)` given back to the
//! tangent).
//! Putting the centre back moves it towards the edge, along the pull that holds
//! it there, so the correction only ever takes energy out. The slice's length
//! bounds the travel across the edge (`r/8` per axis: a turn `δθ ≤ √2/8` rad,
//! so the centre is put back by at most `r/64`) and the travel in all (`r/4`, as
//! every slice), not the sink: about 8 slices a frame at the speed an edge can
//! still hold a marble, where plain slices took 32. Every other tile is searched
//! as in any slice — a second tile it rests on too (two edges under a marble over
//! a slot), which then hands the marble to plain slices — and the fixed step's
//! passes run at each end for what the search leaves to them. A marble that
//! touches an edge slowly but turns round it faster than the edge can hold it,
//! and cannot come closer to it on its flight, flies one slice of the same length
//! past it with its whole pull (`pivot_len`): it leaves the edge, as a real one
//! does, where plain slices brought it back to the edge for a touch each.
//!
//! Measured on the built-in levels' worst frames (`cargo xtask qemu-profile`,
//! the demo's per-level `profile` lines): see `docs/performance.md`.

use super::super::super::dynamics::respond::T_LOG2;
use super::super::super::dynamics::toi::Segment;
use super::super::super::geometry::tiles::TileIndex;
use super::{max_abs, Flight};
use super::{Marble, Scalar, Vec3, World};

/// What [`World::pivot_point`] finds: the edge's nearest point, the unit normal
/// from it to the centre, the edge's axis (`None` at a corner).
pub(super) type PivotPoint<S> = (Vec3<S>, Vec3<S>, Option<usize>);

impl<S: Scalar, const M: usize> World<'_, S, M> {
    /// The point of tile `t` nearest the centre `pos` when it is on an edge or a
    /// corner (two or three axes outside the tile's box), the unit normal from it
    /// to the centre, and the edge's axis (`None` at a corner).
    pub(super) fn pivot_point(&self, pos: Vec3<S>, t: TileIndex) -> Option<PivotPoint<S>> {
        let b = self.params.layout.tile_box(t);
        // Axis by axis, not a loop over an axis index: on the Cortex-M0 the
        // indexed reads and writes of a `Vec3` took about 30 of this function's
        // 220 instructions (ten calls in the v1's worst difficulty-9 frame).
        let (x, out_x) = clamp_out(pos.x, b.min.x, b.max.x);
        let (y, out_y) = clamp_out(pos.y, b.min.y, b.max.y);
        let (z, out_z) = clamp_out(pos.z, b.min.z, b.max.z);
        let along = match (out_x, out_y, out_z) {
            (true, true, true) => None,
            (false, true, true) => Some(0),
            (true, false, true) => Some(1),
            (true, true, false) => Some(2),
            _ => return None,
        };
        let q = Vec3::new(x, y, z);
        let d = pos - q;
        let d2 = d.length_sq();
        if d2 <= S::ZERO {
            return None;
        }
        Some((q, d.scale(d2.rsqrt_fine()), along))
    }

    /// Whether the edge at `point` (its [`World::pivot_point`] from the marble's
    /// centre) holds the marble on the flight `f.seg` (the pull presses it on
    /// harder than the turn needs); if so the flight's normal parts (the pull's and
    /// the velocity's) are dropped.
    pub(super) fn pivot_hold(
        &self,
        m: &Marble<S>,
        f: &mut Flight<S>,
        point: Option<PivotPoint<S>>,
    ) -> bool {
        let Some((_, n, _)) = point else {
            return false;
        };
        let p = &self.params;
        let seg = f.seg;
        // Half the pull along n, pitch/step² (negative: towards the edge).
        // The normal first in its products: an edge's has a zero component,
        // which the Cortex-M0's product answers at once as a first operand
        // (as a second it takes the whole 16-bit product path).
        let hn = n.dot(seg.h);
        if hn >= S::ZERO {
            return false;
        }
        // A pull of 64 pitch/s a step or more on an axis (10 g at the default
        // pitch, beyond any board's tilt and motion) is not held: the part of
        // `dv` along `n` could leave the format (the property test's arbitrary
        // states, 8 g on every axis: `dv·n` was 128.6 pitch/s).
        if max_abs(seg.dv) >= S::from_int(64) {
            return false;
        }
        // The turn needs a_c = u_t²/r; held while −a·n = −2·h·n exceeds it. In
        // pitch/step, |u| < 1 per axis: the squares stay under 3.
        let un = n.dot(seg.u);
        // An edge does not pull: a marble leaving it faster than the threshold
        // (a bounce off another tile inside the slice: the far rim of a gap) is
        // not held, and keeps that speed.
        if un > self.threshold_per_step() {
            return false;
        }
        let ut2 = seg.u.length_sq() - un.times(un);
        if (p.radius + p.radius).times(S::ZERO - hn) <= ut2 {
            return false;
        }
        // |v| ≤ 127 pitch/s (`cap_speed`), so |v·n| ≤ 127 by Cauchy–Schwarz.
        let v = seg.v - n.scale(n.dot(seg.v));
        let dv = seg.dv - n.scale(n.dot(seg.dv));
        f.set_seg(Segment::new(m.pos, v, dv, seg.h - n.scale(hn), p.k));
        true
    }

    /// A pivot slice's length: `2^-j` of the flight's interval, at most 10 halvings,
    /// turning the marble at most 1/8 rad about the edge at `point` (the travel
    /// across the edge at most `r/8`) and moving it at most `r/4` in all.
    ///
    /// `touched`: a slow touch on an edge that does not hold the marble (the turn
    /// needs more than the pull presses it on with, `v_t² ≥ −r·a·n`). If the
    /// marble cannot come closer to the edge on its flight, the slice gets the
    /// same length, the edge left out and the whole pull kept: its distance from
    /// the edge, `|r·n + u⊥·s + h⊥·s²|² = r² + 2r(u⊥·n)s +
    /// (|u⊥|² + 2r(h⊥·n))s² + 2(u⊥·h⊥)s³ + |h⊥|²s⁴` (`⊥`: across the edge; a
    /// corner takes the whole vectors), never shrinks over the slice's `len` steps
    /// when the first two coefficients are not negative and the third takes no more
    /// than the second gives (`a + 2(u⊥·h⊥)·len ≥ 0`, `a` the `s²` coefficient: a
    /// marble just too fast for the edge, its pull leaning back along its path),
    /// so there is no sink to bound the slice by — while the centre stays outside
    /// the tile's box on each axis it is outside on, where the edge's line is the
    /// tile's nearest part: a centre that could cross into a face's range over the
    /// slice is refused (the first coefficient may be rounding's `−r/16384` a step:
    /// the marble then comes at most that far in over the slice's step or less,
    /// within the touching tolerance). Otherwise
    /// `None`: a plain slice. (Plain slices, `2^-5` of the step, took 16 of the 18 units of
    /// drop-onto-marble's worst frame: its marble rolling off a hole's rim nearly
    /// fast enough to leave it, each slice's pull brought it back to the edge for
    /// another touch.) An event inside the slice ends it as a rail slice's does:
    /// the rest is a plain slice.
    // Out of line: one copy for both kinds of world (the micro:bit v1's flash).
    #[inline(never)]
    pub(super) fn pivot_len(
        &self,
        f: &Flight<S>,
        point: Option<PivotPoint<S>>,
        touched: bool,
    ) -> Option<S> {
        let r = self.params.radius;
        let seg = &f.seg;
        let (mut across_u, mut across_h) = (seg.u, seg.h);
        if let Some((_, _, Some(a))) = point {
            across_u.set_axis(a, S::ZERO);
            across_h.set_axis(a, S::ZERO);
        }
        let (um, hm) = (max_abs(seg.u), max_abs(seg.h));
        let (cu, ch) = (max_abs(across_u), max_abs(across_h));
        let mut len = f.len;
        let mut j = 0;
        while j < 10
            && (um.times(len) > r.shr(2)
                || hm.times(len.times(len)) > r.shr(2)
                || cu.times(len) > r.shr(4)
                || ch.times(len.times(len)) > r.shr(4))
        {
            len = len.half();
            j += 1;
        }
        if touched {
            let (_, n, _) = point?;
            // Pitch per step: components under 1, squares under 3. What the
            // touch left of the speed into the edge is rounding (`−2^-24` pitch
            // a step in most touches that did not leave), so up to `r/16384` a
            // step counts as none.
            let a = across_u.length_sq() + (r + r).times(across_h.dot(n));
            let b = across_u.dot(across_h);
            if across_u.dot(n) < S::ZERO - r.shr(14)
                || a < S::ZERO
                || (b < S::ZERO && a + (b + b).times(len) < S::ZERO)
            {
                return None;
            }
            // The quartic is the distance from the edge's line: the tile's while
            // the centre stays outside the box on every axis it is outside on. A
            // centre that could cross into a face's range over the slice would
            // be nearer the face than the line.
            let len2 = len.times(len);
            for axis in 0..3 {
                let out = r.times(n.axis(axis)).abs();
                if out > S::ZERO
                    && across_u.axis(axis).abs().times(len) + across_h.axis(axis).abs().times(len2)
                        >= out
                {
                    return None;
                }
            }
        }
        Some(len)
    }

    /// The end of a pivot slice: the centre back on the sphere about edge tile `t`
    /// (`r` and a tolerance from it) and the velocity along the new tangent, no
    /// faster than it was.
    pub(super) fn onto_pivot(&self, m: &mut Marble<S>, t: TileIndex) {
        let Some((q, n, _)) = self.pivot_point(m.pos, t) else {
            return;
        };
        onto_sphere(m, q, n, self.params.radius + self.tol());
    }

    /// Whether a marble resting on two parallel edges at once — over a slot, the
    /// pull pressing it into both — is held by them; if so the flight keeps only
    /// its parts along the edges (the rail) and the slice is bounded like a pivot
    /// slice's, not by the sink.
    ///
    /// Plain slices over two supports would be `2^-5` step, short enough that
    /// the pull sinks the marble at most `2^-12·r` into either edge before the
    /// passes push it out: 32 slices and 32 touches a frame for a marble lying
    /// still over a slot, every frame a hand on the board changes the pull by a
    /// milli-g (380 k Cortex-M4 instructions; it never falls asleep). Held here
    /// when the pull's part across the edges lies between the two normals
    /// (`−h⊥ = λ₁n₁ + λ₂n₂`, `λ ≥ 0`: the edges' normal forces carry it all) and
    /// the marble moves across them slower than the restitution threshold (a
    /// resting contact: that motion is dropped, as a contact drops it). Moving
    /// along the edges keeps the centre its distance from both: nothing to put
    /// back at the slice's end.
    ///
    /// `point` is `second`'s [`World::pivot_point`] from the marble's centre.
    pub(super) fn rail_hold(
        &self,
        m: &mut Marble<S>,
        f: &mut Flight<S>,
        first: TileIndex,
        second: TileIndex,
        point: Option<PivotPoint<S>>,
    ) -> bool {
        let (Some((_, n1, Some(a1))), Some((_, n2, Some(a2)))) =
            (self.pivot_point(m.pos, first), point)
        else {
            return false;
        };
        if a1 != a2 || first == second {
            return false;
        }
        let p = &self.params;
        let seg = f.seg;
        // The two axes across the edges, and 2-D cross products in that plane:
        // unit normals and a pull under 1 pitch/step² keep every product in range.
        let (b, c) = match a1 {
            0 => (1, 2),
            1 => (0, 2),
            _ => (0, 1),
        };
        let cross =
            |u: Vec3<S>, v: Vec3<S>| u.axis(b).times(v.axis(c)) - u.axis(c).times(v.axis(b));
        // The pull across the edges presses into both...
        let mut pull = seg.h;
        pull.set_axis(a1, S::ZERO);
        if n1.dot(pull) >= S::ZERO || n2.dot(pull) >= S::ZERO {
            return false;
        }
        // ...and `−h⊥` lies between `n₁` and `n₂`: on the same side of each as
        // the other.
        let up = Vec3::ZERO - pull;
        let (s12, s1u, su2) = (cross(n1, n2), cross(n1, up), cross(up, n2));
        let same = |x: S| (x >= S::ZERO) == (s12 >= S::ZERO);
        if s12 == S::ZERO || !same(s1u) || !same(su2) {
            return false;
        }
        // Across the edges slower than the threshold (pitch/step, in squares).
        let mut across = seg.u;
        across.set_axis(a1, S::ZERO);
        let w_t = self.threshold_per_step();
        if across.length_sq() > w_t.times(w_t) {
            return false;
        }
        let along = |v: Vec3<S>| {
            let mut o = Vec3::ZERO;
            o.set_axis(a1, v.axis(a1));
            o
        };
        m.vel = along(m.vel);
        f.set_seg(Segment::new(
            m.pos,
            along(seg.v),
            along(seg.dv),
            along(seg.h),
            p.k,
        ));
        true
    }
}

/// `c` clamped to `[lo, hi]`, and whether it was outside.
#[inline(always)]
fn clamp_out<S: Scalar>(c: S, lo: S, hi: S) -> (S, bool) {
    if c < lo {
        (lo, true)
    } else if c > hi {
        (hi, true)
    } else {
        (c, false)
    }
}

/// The centre put on the sphere of `radius` about `q` along the unit normal `n`
/// from it, and the velocity turned to the sphere's tangent there, no faster
/// than it was (the end of a slice rolling on an edge or a marble).
pub(super) fn onto_sphere<S: Scalar>(m: &mut Marble<S>, q: Vec3<S>, n: Vec3<S>, radius: S) {
    m.pos = q + n.scale(radius);
    // In pitch/T (1/32 s): components ≤ 4, squares ≤ 48.
    let w = m.vel.shr(T_LOG2);
    let wn = n.dot(w);
    if wn > S::ZERO {
        let wt = w - n.scale(wn);
        let (t2, n2) = (wt.length_sq(), wn.times(wn));
        // |wt|·(1 + x/2 − x²/8) ≤ |wt|·√(1 + x) = |w| with x = wn²/|wt|² < 1
        // (the root's series alternates with falling terms). Until 6 December
        // the factor was 1 + x/2, which is more than the root: a pivot slice's
        // end gave back up to x²/8 of the speed more than it took.
        let wt = if n2 < t2 {
            let x = n2.div(t2);
            wt.scale(S::ONE + x.half() - x.times(x).shr(3))
        } else {
            wt
        };
        m.vel = wt.shl(T_LOG2);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use fixed::types::I8F24;
    use rand_core::{Rng, SeedableRng};
    use rand_xorshift::XorShiftRng;

    /// Turning the velocity to the sphere's tangent never speeds the marble up:
    /// beyond rounding (`f64`'s, four LSBs of I8F24's), over random velocities with a
    /// radial part up to nearly the tangential one (`1 + x/2`, the factor until
    /// 6 December, gave back up to `x²/8` of the speed more than it took).
    fn never_faster<S: Scalar>(tol: f64) {
        let mut rng = XorShiftRng::seed_from_u64(0x5eed_0b7e);
        let mut unit = || (rng.next_u32() as f64 / u32::MAX as f64) * 2.0 - 1.0;
        for _ in 0..2000 {
            // A unit normal, and a velocity with a tangential part and an outward
            // radial part no larger than it (pitch/s, within the speed limit).
            let (a, b) = (unit() * core::f64::consts::PI, unit() * 1.5);
            let n = [b.cos() * a.cos(), b.sin(), b.cos() * a.sin()];
            let t = [-a.sin(), 0.0, a.cos()];
            let (vt, vn) = (unit().abs() * 60.0 + 1.0, unit().abs());
            let v: [f64; 3] = core::array::from_fn(|i| vt * t[i] + vt * vn * n[i]);
            let to =
                |c: [f64; 3]| Vec3::new(S::from_f64(c[0]), S::from_f64(c[1]), S::from_f64(c[2]));
            let mut m = Marble {
                pos: Vec3::ZERO,
                vel: to(v),
                supported: true,
                out: false,
                asleep: false,
                rest_mask: 0,
                rest_plane: [S::ZERO; 3],
            };
            let speed = |m: &Marble<S>| m.vel.to_f64().iter().map(|c| c * c).sum::<f64>().sqrt();
            let before = speed(&m);
            onto_sphere(&mut m, Vec3::ZERO, to(n), S::from_f64(0.3));
            let after = speed(&m);
            assert!(
                after <= before * (1.0 + 1e-12) + tol,
                "{before} -> {after} (v {v:?}, n {n:?})"
            );
        }
    }

    #[test]
    fn onto_the_sphere_is_never_faster() {
        never_faster::<f64>(0.0);
        never_faster::<I8F24>(4.0 * I8F24::DELTA.to_num::<f64>() * 128.0);
    }
}
