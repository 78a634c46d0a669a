//! The quiet frame of a marble rolling along the one wall it is held on, in a
//! flat world: the maze's commonest frame (the tilt presses the marble into a
//! wall and rolls it along). Across the wall nothing moves — the hold drops
//! the pull there, the speed there is zero — so the quiet frame's sums on that
//! axis and on y' are the centre's own coordinate plus zeros, and the flight is
//! one axis's closed form. Here those sums are made on that axis alone, with
//! the wall's axis a constant: the same bits as `quiet_frame` (debug builds
//! fly it beside and compare), without the vector sums, the loop over the held
//! faces and the acceleration's struct that it pays for.
//!
//! Only where `quiet_frame` would serve the frame: anything else (no wall or
//! two, a face the hold lets go of, a region that does not back the wall or
//! hold the path, rolling resistance's interval or stop inside the step, the
//! board turning, an observer) is left to it, with nothing changed.

use super::super::super::geometry::sweep::swept_axis;
use super::super::super::geometry::tiles::Aabb;
use super::{cap_speed, Marble, Scalar, Vec3, World, SEARCH};

impl<S: Scalar, const M: usize> World<'_, S, M> {
    /// Flies marble `n`'s step if it is a quiet frame rolling along one wall
    /// of a flat world (then `true`, the marble moved); else `false` and
    /// nothing changed. Out of line: the inlined step only calls it. Debug
    /// builds fly the quiet frame beside it and compare what each leaves.
    #[inline(never)]
    pub(super) fn roll_along(&mut self, n: usize, m: &mut Marble<S>) -> bool {
        #[cfg(debug_assertions)]
        let twin = (self.clone(), *m);
        let served = self.roll_along_in(n, m);
        #[cfg(debug_assertions)]
        if served {
            let (mut w, mut t) = twin;
            let quiet = w.quiet_frame::<false, ()>(n, &mut t, &mut ());
            let bits = |v: Vec3<S>| [v.x.hash_bits(), v.y.hash_bits(), v.z.hash_bits()];
            assert!(quiet.is_none(), "marble {n}: rolled along, not served");
            assert_eq!((bits(t.pos), bits(t.vel)), (bits(m.pos), bits(m.vel)));
            assert_eq!((t.rest_mask, t.supported), (m.rest_mask, m.supported));
            assert_eq!((w.stats, w.flights_left), (self.stats, self.flights_left));
        }
        served
    }

    /// [`World::roll_along`].
    #[inline(always)]
    fn roll_along_in(&mut self, n: usize, m: &mut Marble<S>) -> bool {
        let fx = self.params.spec.effects;
        debug_assert!(fx.friction, "asked only with rolling resistance");
        if fx.board_motion || self.out_of_flights() {
            return false;
        }
        // Bit `2·axis + up`: one face, on x' (rolling along z') or z'.
        match m.rest_mask {
            0b01 | 0b10 => self.roll_on::<0, 2>(n, m),
            0b01_0000 | 0b10_0000 => self.roll_on::<2, 0>(n, m),
            _ => false,
        }
    }

    /// [`World::roll_along`] held on a face of axis `H`, rolling along axis
    /// `A`.
    #[inline(always)]
    fn roll_on<const H: usize, const A: usize>(&mut self, n: usize, m: &mut Marble<S>) -> bool {
        // Held from above (`up`): the face's bit is the axis's odd one.
        let up = m.rest_mask & (0b10 << (2 * H)) != 0;
        let region = &self.free[n];
        // The region built with this face, backing it under the centre
        // (`under_held`), as the served quiet frame asks of a held marble.
        if !region.built_with(m.rest_mask) || !region.under_face::<H>(m, up) {
            return false;
        }
        // The hold keeps the face: the centre on it, no speed across it, the
        // pull pressing it in (its tile known backed by the region).
        let r = self.params.radius;
        let plane = m.rest_plane[H];
        let at = if up { plane + r } else { plane - r };
        let kick = &self.kick_roll;
        let pull = kick.dv.axis(H);
        let presses = if up { pull < S::ZERO } else { pull > S::ZERO };
        if m.pos.axis(H) != at || m.vel.axis(H) != S::ZERO || !presses {
            return false;
        }
        // The hold drops the pull across the face (and the plane's y'): what
        // is left is the pull along `A`. Rolling resistance as
        // `Drag::flight` makes it of a velocity and a pull along `A` alone:
        // its one-axis sums, the whole step one interval; at rest and held,
        // no kick.
        let (mut dv, mut h) = (kick.dv.axis(A), kick.dp.axis(A));
        let v = m.vel.axis(A);
        match self.drag.along(v, &mut dv, &mut h, S::ONE) {
            Some((_, stop, _)) => {
                if stop.is_some_and(|s| s < S::ONE) {
                    return false;
                }
            }
            None => (dv, h) = (S::ZERO, S::ZERO),
        }
        // The whole step's closed form along `A` (`Segment::pos_at(1)`:
        // `p + (u + h)`, `u = v·dt`; `vel_at(1)`: `v + dv`, saturating);
        // across, the centre plus zeros, whose sums a fixed-point format
        // folds away and a float one makes as `quiet` does.
        let k = self.params.k;
        let p = m.pos.axis(A);
        let end_a = p + (v.shr(k) + h);
        let zero = S::ZERO.shr(k) + S::ZERO;
        let (end_h, end_y) = (m.pos.axis(H) + zero, m.pos.y + zero);
        // The swept box (`swept`): along `A` as `swept_axis` makes it; across,
        // with no bend, its two ends in order (`swept_axis` with `h` zero);
        // y' a flat world's region does not ask.
        let (lo_a, hi_a) = swept_axis(p, end_a, h, None);
        let p_h = m.pos.axis(H);
        let (lo_h, hi_h) = if p_h < end_h {
            (p_h, end_h)
        } else {
            (end_h, p_h)
        };
        let mut path = Aabb {
            min: Vec3::new(lo_h, m.pos.y, lo_h),
            max: Vec3::new(hi_h, m.pos.y, hi_h),
        };
        path.min.set_axis(A, lo_a);
        path.max.set_axis(A, hi_a);
        if !region.contains(&path, r + self.tol(), false) {
            return false;
        }
        // Served: the quiet frame's bookkeeping and its end.
        self.spend(1, SEARCH);
        self.stats.free_served = self.stats.free_served.wrapping_add(1);
        let mut end = Vec3::new(end_h, end_y, end_h);
        end.set_axis(A, end_a);
        let mut vel = Vec3::new(
            m.vel.axis(H).sat_add(S::ZERO),
            S::ZERO.sat_add(S::ZERO),
            m.vel.axis(H).sat_add(S::ZERO),
        );
        vel.set_axis(A, v.sat_add(dv));
        m.pos = end;
        m.vel = cap_speed(vel);
        true
    }
}
