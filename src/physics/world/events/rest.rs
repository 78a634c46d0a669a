//! A marble on a marble standing still: rolling on it, and a resting pair
//! (issue 40).
//!
//! A marble that lands on another lying still — down a hole onto the marble
//! below — is pressed on it by the pull, and a pair pressed together goes on in
//! pair slices (`together.rs`): both marbles flown, the pair pushed apart, the
//! tile passes, each slice short enough that the pull sinks the pair at most
//! `2^-12·r` (`2^-5` step). Rolling over the lower marble into the cradle of the
//! hole's rim and that marble, it trembled there by hundredths of a micrometre, a
//! few mm/s into its supports, and the pair flew 32 slices a step until the exact
//! sleep test found a whole step that changed nothing (seven frames of 400 k
//! instructions on the Cortex-M4F; with the flight budget, 45 frames cut at the
//! budget: the scene in slow motion).
//!
//! A marble **stands still** for the rest of its step when it has no velocity and
//! its flight none (its held faces carry its pull, or it sleeps: the same test
//! either way, so that sleeping stays a pure cache). A marble touching one that
//! stands still, slower than the restitution threshold, where the still one's
//! held faces carry the push (the pair's normal has no part along an axis on
//! which it is not held from that side), is asked at its next flight:
//! - whether it **rests** there: it touches a tile too, an edge or a face it is
//!   held on, whose normal and the pair's lie across one axis (the rail both
//!   supports leave free), the pull (what its held faces and rolling resistance
//!   leave of it) lies in the cone of the two normals across that axis — their
//!   normal forces carry all of it — with no part along the rail, and it moves
//!   slower than the threshold. Its velocity is then zeroed (a resting contact
//!   drops that motion, as a contact does) and it stays where it is for the rest
//!   of the step; the next step finds it there and the sleep test puts it to
//!   sleep.
//! - else whether it **rolls** on it, as a pivot slice rolls round a corner
//!   (`pivot.rs`, on a sphere of radius `2r` about the still marble's centre):
//!   while the pull presses it on harder than the turn needs, the flight's parts
//!   along the pair's normal are dropped, every tile is searched, and at the
//!   slice's end the centre is put back `2r` (and a tolerance) from the still
//!   one's, the velocity along the new tangent and no faster.
//! - else the pair goes on as any pair (asked again only once the marble has
//!   moved).
//!
//! A marble that touches one standing still **faster** than the threshold, where
//! the still one's held faces carry the push, **strikes** it: eq. 1 against it as
//! against a wall (the still marble and what holds it are one rigid support: the
//! impulse passes through it into the faces), the moving marble's normal speed
//! reversed and scaled by the restitution. A marble dropped down a hole onto one
//! lying against the wall below once woke it, and the pair flew pair slices.
//!
//! The still marble is not woken: nothing moves it. Only motion below the
//! threshold is dropped and the centre is put back only towards the still marble,
//! along the pull: no energy is gained, nothing moves into anything, and the rule
//! is a pure function of the state, the same on every target.

use super::super::super::geometry::broadphase::{candidates, candidates_plane};
use super::super::super::geometry::narrowphase::unit;
use super::pivot::onto_sphere;
use super::{
    cap_speed, max_abs, no_faster, Contact, Flight, Marble, Scalar, Segment, Slice, TileIndex,
    Vec3, World, EVERY, T_LOG2,
};

impl<S: Scalar, const M: usize> World<'_, S, M> {
    /// Whether marble `m`, at the state its flight `f` has brought it to, rests
    /// on the still marble `lo` and a tile: an edge it touches or a face it is
    /// held on (see the module doc). `space`: the world has holes (3-D).
    // Out of line: one copy for both kinds of world (the micro:bit v1's flash).
    #[inline(never)]
    pub(super) fn rests_on(
        &self,
        m: &Marble<S>,
        lo: &Marble<S>,
        f: &Flight<S>,
        space: bool,
    ) -> bool {
        let p = &self.params;
        let (r, tol) = (p.radius, self.tol());
        if lo.vel != Vec3::ZERO {
            return false;
        }
        let Some(n) = self.held_normal(m, lo) else {
            return false;
        };
        let d = m.pos - lo.pos;
        let w_t = self.threshold_per_step();
        let u = m.vel.shr(p.k);
        if max_abs(u) > w_t {
            return false;
        }
        let h = f.seg.h;
        // Across an axis of each support: the pair's normal has no part along it
        // (the two at one height, within the tolerance).
        let rail = |n1: Vec3<S>, axis: usize| {
            n1.axis(axis) == S::ZERO && d.axis(axis).abs() <= tol && cradle(n, n1, axis, h, u, w_t)
        };
        // The edges in touch (`pivot_point`: none where a face is the tile's
        // nearest part; over a seam of two solid tiles, the face's own normal).
        let reach = r + tol + tol;
        let (layout, tiles) = (&p.layout, self.tiles);
        let range = if space {
            candidates(layout, m.pos, reach)
        } else {
            candidates_plane(layout, m.pos, reach)
        };
        for k in range.lo.k..=range.hi.k {
            for j in range.lo.j..=range.hi.j {
                for i in range.lo.i..=range.hi.i {
                    let t = TileIndex::new(i, j, k);
                    if !tiles.is_solid(t) {
                        continue;
                    }
                    if let Some((q, n1, Some(axis))) = self.pivot_point(m.pos, t) {
                        if n1.dot(m.pos - q) <= reach && rail(n1, axis) {
                            return true;
                        }
                    }
                }
            }
        }
        let mut bits = m.rest_mask;
        while bits != 0 {
            let bit = bits.trailing_zeros() as usize;
            bits &= bits - 1;
            let (axis, up) = (bit / 2, bit % 2 == 1);
            let n1 = unit(axis, up);
            if (0..3).any(|other| other != axis && rail(n1, other)) {
                return true;
            }
        }
        false
    }
}

impl<S: Scalar, const M: usize> World<'_, S, M> {
    /// Of marbles `a` and `b` touching at `when` (the pair's `contact`, `None`
    /// inside each other), the one that moves and the still one it meets, and
    /// whether it touches slowly: then only if it has not been asked whether it
    /// rests or rolls there since its flight last moved it.
    // Out of line, and so are the rest's: one copy for both kinds of world (the
    // micro:bit v1's flash).
    #[inline(never)]
    pub(super) fn lying(
        &self,
        fl: &[Flight<S>; M],
        a: usize,
        b: usize,
        contact: Option<&Contact<S>>,
        when: S,
    ) -> Option<(usize, u8, bool)> {
        let (ma, mb) = (&self.marbles[a], &self.marbles[b]);
        let (up, lo) = match (still(ma, &fl[a]), still(mb, &fl[b])) {
            (true, false) => (b, a),
            (false, true) => (a, b),
            _ => return None,
        };
        // Slower than the threshold, as `pair_touch` asks; a faster touch is a
        // strike (`World::strike`).
        let slow = contact.is_none_or(|c| {
            c.normal.dot(ma.vel.shr(T_LOG2) - mb.vel.shr(T_LOG2)) <= self.params.threshold
        });
        let lo = lo as u8;
        (!slow || fl[up].tried != Some(lo) || when > fl[up].t).then_some((up, lo, slow))
    }

    /// Marble `m` striking the still marble `lo` faster than the threshold: when
    /// `lo`'s held faces carry the push, eq. 1 against `lo` as against a wall
    /// (`lo` and what holds it are one rigid support: the impulse passes through
    /// it into the faces), `m`'s normal speed reversed and scaled by the
    /// restitution, `lo` not woken. Returns whether it did. (A landing on a
    /// marble lying against a wall woke it, and the pair flew pair slices.)
    #[inline(never)]
    pub(super) fn strike(&mut self, m: &mut Marble<S>, lo: u8) -> bool {
        let p = self.params;
        let Some(n) = self.held_normal(m, &self.marbles[lo as usize]) else {
            return false;
        };
        // |v| ≤ 127 pitch/s (`cap_speed`), so |v·n| ≤ 127; the new normal speed
        // is formed in pitch/T (≤ 4 a component), as `pair_touch` forms it.
        let vn = n.dot(m.vel);
        if vn >= S::ZERO {
            return false;
        }
        let w = S::ZERO - vn.shr(T_LOG2);
        let out = p.restitution.times(w).shl(T_LOG2).min(p.v_max);
        let t = m.vel - n.scale(vn);
        let v = Vec3::new(
            t.x.sat_add(n.x.times(out)),
            t.y.sat_add(n.y.times(out)),
            t.z.sat_add(n.z.times(out)),
        );
        m.vel = no_faster(cap_speed(v), m.vel);
        self.impacts.record(w.shl(T_LOG2));
        self.stats.collisions = self.stats.collisions.wrapping_add(1);
        m.asleep = false;
        true
    }

    /// The unit normal from `lo`'s centre to `m`'s, when they touch (within `2r`
    /// and two tolerances) and what holds `lo` carries a push along it
    /// ([`carried`]): the pair's normal every rule here starts from.
    fn held_normal(&self, m: &Marble<S>, lo: &Marble<S>) -> Option<Vec3<S>> {
        let (r, tol) = (self.params.radius, self.tol());
        let n = normal(m.pos - lo.pos, r + r + tol + tol)?;
        carried(lo.rest_mask, n).then_some(n)
    }

    /// Whether marble `n` stands still for the rest of its step (see [`still`]).
    #[inline(never)]
    pub(super) fn stands_still(&self, fl: &[Flight<S>; M], n: usize) -> bool {
        still(&self.marbles[n], &fl[n])
    }

    /// Whether marble `x` rolls or rests on marble `y` while `y` stays still:
    /// their pair is not tested (the roll slice keeps them touching, the rest
    /// keeps both where they are). Inline: every pair test asks it, and most
    /// marbles lie on none.
    #[inline]
    pub(super) fn lies_on(&self, fl: &[Flight<S>; M], x: usize, y: usize) -> bool {
        let y8 = Some(y as u8);
        (fl[x].rest == y8 || fl[x].slice.is_some_and(|sl| sl.on == y8)) && self.stands_still(fl, y)
    }

    /// Whether the sleeping marble `lo` holds marble `m` on the flight `f.seg`
    /// (the pull presses it on harder than its turn about `lo` needs, its held
    /// faces carry the push, it touches `lo` slower than the restitution
    /// threshold); if so the flight's parts along the pair's normal (the pull's
    /// and the velocity's) are dropped, as an edge's are (`pivot.rs`), on a
    /// sphere of radius `2r` about `lo`'s centre.
    pub(super) fn roll_hold(&self, m: &Marble<S>, f: &mut Flight<S>, lo: u8) -> bool {
        // Still, as it was when the roll began (`together.rs` asks the whole
        // flight): a marble struck meanwhile moves.
        let other = &self.marbles[lo as usize];
        if other.vel != Vec3::ZERO {
            return false;
        }
        let Some(n) = self.held_normal(m, other) else {
            return false;
        };
        let (p, r) = (&self.params, self.params.radius);
        let seg = f.seg;
        // The normal first in its products (a zero component is the Cortex-M0's
        // short path).
        let hn = n.dot(seg.h);
        if hn >= S::ZERO || max_abs(seg.dv) >= S::from_int(64) {
            return false;
        }
        // Touching slowly either way (pitch/step; |u| < 1 per axis).
        let (un, w_t) = (n.dot(seg.u), self.threshold_per_step());
        if un > w_t || un < S::ZERO - w_t {
            return false;
        }
        // The turn about lo's centre needs u_t²/(2r); held while −a·n = −2·h·n
        // exceeds it.
        let ut2 = seg.u.length_sq() - un.times(un);
        let r4 = (r + r).shl(1);
        if r4.times(S::ZERO - hn) <= ut2 {
            return false;
        }
        let v = seg.v - n.scale(n.dot(seg.v));
        let dv = seg.dv - n.scale(n.dot(seg.dv));
        f.set_seg(Segment::new(m.pos, v, dv, seg.h - n.scale(hn), p.k));
        true
    }

    /// A slice rolling on the sleeping marble `lo` while it holds marble `m`
    /// ([`World::roll_hold`]), as long as a pivot slice about a corner
    /// (`pivot_len`: a turn of at most 1/16 rad about `lo`, half a pivot's about
    /// an edge, and `r/4` of travel); else none (a plain flight: a marble the
    /// turn lifts off `lo` leaves it).
    pub(super) fn roll_slice(&mut self, m: &Marble<S>, f: &mut Flight<S>, lo: u8) -> bool {
        if !self.roll_hold(m, f, lo) {
            return false;
        }
        // Rolling: a later touch on it may roll again.
        f.tried = None;
        let len = self.pivot_len(f, None, false).unwrap_or(f.len);
        f.slice = Some(Slice {
            skip: EVERY,
            start: m.pos,
            from: f.t,
            to: f.after(len),
            pivot: false,
            rail: false,
            on: Some(lo),
        });
        self.stats.slices = self.stats.slices.wrapping_add(1);
        true
    }

    /// The end of a slice rolling on marble `lo`: the centre back within `2r`
    /// and a tolerance of `lo`'s — in from further (the slice's tangent leaves
    /// the sphere outwards: along the pull that holds it there, energy only
    /// taken out), out from nearer than `2r` — the velocity along the tangent
    /// there, no faster than it was.
    pub(super) fn onto_marble(&self, m: &mut Marble<S>, lo: u8) {
        let q = self.marbles[lo as usize].pos;
        let (r, tol) = (self.params.radius, self.tol());
        let (near, far) = (r + r, r + r + tol);
        let d = m.pos - q;
        let Some(n) = normal(d, far + r) else {
            return;
        };
        let d2 = d.length_sq();
        let at = if d2 > far.times(far) {
            far
        } else if d2 < near.times(near) {
            near
        } else {
            return;
        };
        onto_sphere(m, q, n, at);
    }
}

/// The unit vector along `d`, if `d` is shorter than `near` (on every axis
/// first: the square of a far separation leaves I8F24's range) and not zero.
fn normal<S: Scalar>(d: Vec3<S>, near: S) -> Option<Vec3<S>> {
    if max_abs(d) > near {
        return None;
    }
    let d2 = d.length_sq();
    if d2 > near.times(near) || d2 <= S::ZERO {
        return None;
    }
    Some(d.scale(d2.rsqrt_fine()))
}

/// Whether a marble lying on faces `mask` (bit `2·axis + up`) is held against a
/// push along `−n`: on every axis the push has a part on (more than 1/64 of it),
/// a face held from that side.
fn carried<S: Scalar>(mask: u8, n: Vec3<S>) -> bool {
    let small = S::ONE.shr(6);
    (0..3).all(|axis| {
        let c = n.axis(axis);
        // Pushed towards −axis when `n` points up it: a face whose normal points
        // up the axis (bit `2·axis + 1`) carries it.
        (c.abs() <= small) || mask & (1 << (2 * axis + (c > S::ZERO) as usize)) != 0
    })
}

/// Whether the supports with unit normals `n1` and `n2`, both across axis `rail`,
/// carry the pull `h` (its part across the rail lies between them, none along it)
/// of a marble moving `u` a step, slower than `w_t` across them.
fn cradle<S: Scalar>(
    n1: Vec3<S>,
    n2: Vec3<S>,
    rail: usize,
    h: Vec3<S>,
    u: Vec3<S>,
    w_t: S,
) -> bool {
    if h.axis(rail) != S::ZERO {
        return false;
    }
    let (b, c) = match rail {
        0 => (1, 2),
        1 => (0, 2),
        _ => (0, 1),
    };
    let mut across = u;
    across.set_axis(rail, S::ZERO);
    if across.length_sq() > w_t.times(w_t) {
        return false;
    }
    // 2-D cross products across the rail: unit normals and a pull under 1
    // pitch/step² keep every product in range.
    let cross = |x: Vec3<S>, y: Vec3<S>| x.axis(b).times(y.axis(c)) - x.axis(c).times(y.axis(b));
    // `−h` on the same side of each normal as the other: between them (the
    // normals at an obtuse angle, the pull may lean away from one and still
    // press the marble into it through the other).
    let up = Vec3::ZERO - h;
    let (s12, s1u, su2) = (cross(n1, n2), cross(n1, up), cross(up, n2));
    let same = |x: S| (x >= S::ZERO) == (s12 >= S::ZERO);
    s12 != S::ZERO && same(s1u) && same(su2)
}

/// A marble standing still for the rest of its step: no velocity, and a flight
/// with none (its held faces carry its pull, or it sleeps).
fn still<S: Scalar>(m: &Marble<S>, f: &Flight<S>) -> bool {
    let z = Vec3::ZERO;
    m.vel == z && f.seg.u == z && f.seg.dv == z && f.seg.h == z
}
