//! The earliest event of a flight: the reach test, then the time of impact of
//! every tile in reach (and the lid), the end of a held face's support, and what
//! a slice leaves out.

use super::{
    entry, offset, owned, reach, shadowed, swept, toi_box, Aabb, Contact, Event, Feature, Flight,
    Marble, Scalar, Segment, TileIndex, TileRange, Toi, Vec3, World, EVERY, LID, TILE,
};

impl<S: Scalar, const M: usize> World<'_, S, M> {
    /// The earliest event of the flight `f` within `limit` steps, leaving tile
    /// `skip` out (a slice's; [`EVERY`] for none) and, if `rest_out`, every tile
    /// the marble rests against (a plain slice's: its passes take them).
    pub(super) fn search<const SPACE: bool>(
        &mut self,
        n: usize,
        m: &Marble<S>,
        f: &mut Flight<S>,
        limit: S,
        skip: TileIndex,
        rest_out: bool,
    ) -> (S, Event<S>) {
        let p = &self.params;
        // The layout copied (three words), so that the tile loop may charge the
        // budget through `self`.
        let (r, layout, tiles) = (p.radius, p.layout, self.tiles);
        let end = f.seg.pos_at(limit);
        f.end = Some((limit, end));
        let seg = &f.seg;
        let tol = self.tol();
        let mut best = (limit, Event::End);
        if let Some(s) = f.stop {
            if s < best.0 {
                best = (s, Event::Stop);
            }
        }
        let path = swept(seg.p, end, seg.h, limit);
        let reach_r = r + tol;
        if self.free[n].serves(m, seg, &path, (r, reach_r), SPACE) {
            self.stats.free_served = self.stats.free_served.wrapping_add(1);
            return best;
        }
        // Held faces: the tile behind the contact point must stay there.
        let mut bits = m.rest_mask;
        while bits != 0 {
            let bit = bits.trailing_zeros() as u8;
            bits &= bits - 1;
            if let Some((s, done)) = self.support_ends::<SPACE>(m, bit, seg, &path, best.0) {
                if s < best.0 {
                    best = (
                        s,
                        if done {
                            Event::Release(bit)
                        } else {
                            Event::Later
                        },
                    );
                }
            }
        }
        // In a slice, every tile the marble rests against is left out like the
        // slice's own: the passes at the slice's end take the slow contacts, as
        // fixed steps do. Where a marble rolls over an edge that two floor tiles
        // share, the two would otherwise hand the slice back and forth, a
        // zero-length event each, until the step's event budget ran out and
        // blind slices flew the marble up to 9 µm into the next edge (a slot
        // beside a hole, on one storey or several).
        // A pivot slice leaves out only its edge: another tile it rests against
        // would be sunk into over the pivot slice's length (two edges under a
        // marble over a slot), so it is found at once and a plain slice takes over.
        // (A pair slice's search has no tile of its own, `EVERY`, and leaves
        // out what each marble rests against all the same.)
        let slicing = rest_out && skip != LID;
        // A pivot slice (`!rest_out`) keeps its edge out without asking: its
        // flight has no part along the edge's normal (`pivot_hold` dropped it), so
        // it neither closes on the edge nor has left it (205 host instructions a
        // pivot slice, five in a roll round a rim; the same states in every replay
        // of the levels, the stress scenes and 800 generated mazes).
        let skip =
            if skip == EVERY || skip == LID || !rest_out || self.still_skipped(seg, skip, limit) {
                skip
            } else {
                EVERY
            };
        // Tiles in reach (plain loops: iterator adapters cost more than the test).
        let mut range = reach(&layout, &path, reach_r, SPACE);
        self.leave_out_held(m, &mut range);
        let mut empty = true;
        let mut k = range.lo.k;
        while k <= range.hi.k {
            let mut j = range.lo.j;
            while j <= range.hi.j {
                let mut i = range.lo.i;
                while i <= range.hi.i {
                    let t = TileIndex::new(i, j, k);
                    let solid = tiles.is_solid(t);
                    empty &= !solid;
                    if solid && t != skip && !(slicing && self.still_skipped(seg, t, limit)) {
                        let b = layout.tile_box(t);
                        // `leave_out_held` left exactly the tiles not behind a held face.
                        debug_assert!(!behind_held(m, &b));
                        self.charge(TILE);
                        match toi_box(seg, r, &b, best.0, tol) {
                            Toi::Hit { at, contact, d } => {
                                if at < best.0 {
                                    // The ghost-bump rule: a touch on a seam
                                    // belongs to the surface of the tiles.
                                    let c = if shadowed(t, d, tiles) {
                                        owned(t, &b, d, r, tiles).filter(|c| closes(seg, at, c))
                                    } else {
                                        Some(contact)
                                    };
                                    if let Some(c) = c {
                                        best = (at, Event::Touch(c, t));
                                    }
                                }
                            }
                            Toi::Inside { at } => {
                                if at <= best.0 {
                                    best = (at, Event::Inside(t));
                                }
                            }
                            Toi::Later(at) => {
                                if at < best.0 {
                                    best = (at, Event::Later);
                                }
                            }
                            Toi::Miss => {}
                        }
                    }
                    i += 1;
                }
                j += 1;
            }
            k += 1;
        }
        let lid_y = if SPACE { self.lid() } else { S::ZERO };
        if SPACE && skip != LID && path.max.y + reach_r >= lid_y {
            let lid = Aabb {
                min: Vec3::new(S::from_int(-127), lid_y, S::from_int(-127)),
                max: Vec3::new(S::from_int(127), S::from_int(127), S::from_int(127)),
            };
            if !behind_held(m, &lid) {
                match toi_box(seg, r, &lid, best.0, tol) {
                    Toi::Hit { at, contact, .. } if at < best.0 => {
                        best = (at, Event::Touch(contact, LID));
                    }
                    Toi::Inside { at } if at <= best.0 => best = (at, Event::Inside(LID)),
                    Toi::Later(at) if at < best.0 => best = (at, Event::Later),
                    _ => {}
                }
            }
        }
        if empty && self.free_regions && !f.built && matches!(best.1, Event::End | Event::Stop) {
            f.built = true;
            self.build_free(n, m, &path, &range, SPACE);
        }
        best
    }

    /// Narrows `range` by the faces the marble is held on: the rows of tiles
    /// behind a held face cannot be touched, and a marble rolling along a wall
    /// would otherwise look up every tile of that wall in reach, every frame.
    /// Tiles meet at the face's plane (eq. 5), so the rows behind it are those
    /// on the far side of the tile that starts there: exactly the tiles
    /// [`behind_held`] would refuse (eq. 6 and eq. 5 agree on every boundary),
    /// so the search need not ask it per tile (debug builds still check).
    #[inline(never)]
    pub(super) fn leave_out_held(&self, m: &Marble<S>, range: &mut TileRange) {
        let layout = &self.params.layout;
        let mut bits = m.rest_mask;
        while bits != 0 {
            let bit = bits.trailing_zeros() as usize;
            bits &= bits - 1;
            let (axis, up) = (bit / 2, bit % 2 == 1);
            let plane = m.rest_plane[axis];
            let (at, starts) = if axis == 1 {
                let at = layout.index_y(plane);
                (at, layout.span_y(at).0)
            } else {
                let at = layout.index_xz(plane);
                (at, layout.span_xz(at).0)
            };
            let (lo, hi) = range.axis_mut(axis);
            if up {
                // Held from above: every row before `at` ends at or below the plane.
                *lo = (*lo).max(at);
            } else {
                // Held from below: the rows from the first one starting at or above
                // the plane on.
                let first = if starts >= plane { at } else { at + 1 };
                *hi = (*hi).min(first - 1);
            }
        }
    }

    /// Whether a slice still leaves its own tile `skip` out of the flight `seg`:
    /// only while the marble rests on it, at most two tolerances off and not
    /// closing faster than the restitution threshold. A marble that has left it
    /// (bounced off the wall across a narrow corridor, say) and flies back is
    /// searched against it like against any tile: the passes at the slice's end
    /// are for the slow contact the slice was begun for, and a return at speed
    /// would sink into the tile until then (47 µm at 1 pitch/s in a narrow
    /// corridor). Nor while it closes fast enough to sink more than `2^-12·r`
    /// into the tile within the slice's `limit` steps: a marble over a slot,
    /// rolling round one edge, closes on the other at up to the threshold, which
    /// over a slice sinks it `1.3·10⁻³ r` in.
    fn still_skipped(&self, seg: &Segment<S>, skip: TileIndex, limit: S) -> bool {
        let p = &self.params;
        let (r, tol) = (p.radius, self.tol());
        let d = offset(seg.p, &p.layout.tile_box(skip));
        let near = r + tol + tol;
        if d.x.abs() > near || d.y.abs() > near || d.z.abs() > near {
            return false;
        }
        let d2 = d.length_sq();
        if d2 > near.times(near) {
            return false;
        }
        // Closing at `w = −u·d/|d|` (pitch/step) faster than the threshold, in
        // squares: (u·d)² > w_t²·|d|².
        let ud = d.dot(seg.u);
        let w_t = self.threshold_per_step();
        if ud >= S::ZERO {
            return true;
        }
        // Sinking `w·limit` with `|d| ≈ r` (resting, a tolerance off): `−u·d·limit`
        // against `r²/4096`; |u| < 1 per axis and |d| ≤ 2r keep both in range.
        ud.times(ud) <= w_t.times(w_t).times(d2)
            && (S::ZERO - ud).times(limit) <= r.times(r).shr(12)
    }

    /// When the centre, flying `seg`, first enters a column whose tile behind held
    /// face `bit` is missing: `(time, exact)`, within `limit` steps.
    fn support_ends<const SPACE: bool>(
        &self,
        m: &Marble<S>,
        bit: u8,
        seg: &Segment<S>,
        path: &Aabb<S>,
        limit: S,
    ) -> Option<(S, bool)> {
        let (axis, up) = ((bit / 2) as usize, bit % 2 == 1);
        if axis == 1 && !up {
            return None; // the lid is everywhere
        }
        let layout = &self.params.layout;
        let plane = m.rest_plane[axis];
        let behind = if up { plane.next_down() } else { plane };
        let (mut i0, mut i1) = (layout.index_xz(path.min.x), layout.index_xz(path.max.x));
        let (mut k0, mut k1) = (layout.index_xz(path.min.z), layout.index_xz(path.max.z));
        let (mut j0, mut j1) = if SPACE {
            (layout.index_y(path.min.y), layout.index_y(path.max.y))
        } else {
            (1, 1)
        };
        match axis {
            0 => (i0, i1) = (layout.index_xz(behind), layout.index_xz(behind)),
            1 => (j0, j1) = (layout.index_y(behind), layout.index_y(behind)),
            _ => (k0, k1) = (layout.index_xz(behind), layout.index_xz(behind)),
        }
        let axes = [axis != 0, SPACE && axis != 1, axis != 2];
        let mut first: Option<(S, bool)> = None;
        for k in k0..=k1 {
            for j in j0..=j1 {
                for i in i0..=i1 {
                    let t = TileIndex::new(i, j, k);
                    if self.tiles.is_solid(t) {
                        continue;
                    }
                    // Eq. 5's columns are `[lo, hi)`: a centre on `hi` is still in
                    // the next one, which holds the face (eq. 6 says so, and the
                    // hold asks eq. 6). Entering through `hi` at the closed end
                    // would release the face on the seam, a touch hold it again
                    // at once, and the two take turns until the idle rule flew a
                    // blind slice into the next wall (at 28 pitch/s: 3.7·10⁻³ r
                    // in).
                    let b = layout.tile_box(t);
                    let hi = Vec3::new(
                        b.max.x.next_down(),
                        b.max.y.next_down(),
                        b.max.z.next_down(),
                    );
                    if let Some(e) = entry(seg, b.min, hi, axes, limit) {
                        if first.is_none_or(|f| e.0 < f.0) {
                            first = Some(e);
                        }
                    }
                }
            }
        }
        first
    }
}

/// Whether a touch that the ghost-bump rule moved from a seam onto the face of
/// the tiles' union (`owned`) is one: the marble comes towards that face, now or
/// pulled back later. A marble rolling along a wall past the seam of two of its
/// tiles, its pull away from the wall, is within the touching tolerance of the
/// seam's rounded edge for a while (the edge's normal leans along the wall, against
/// the marble's motion, so the edge reads as approached) and meets the face it
/// belongs to not at all: the distance to the face never shrinks, and it bounds
/// the distance to the tile. Taken as a touch it came back with no time passing
/// until the idle rule's blind slices flew the rest of the step.
fn closes<S: Scalar>(seg: &Segment<S>, at: S, c: &Contact<S>) -> bool {
    if !matches!(c.feature, Feature::Face(_)) {
        return true;
    }
    seg.u_at(at).dot(c.normal) < S::ZERO || seg.h.dot(c.normal) < S::ZERO
}

/// Whether the box `b` lies behind a face the marble is held on (then it cannot be
/// touched: the centre stays a radius in front of that face).
#[inline]
fn behind_held<S: Scalar>(m: &Marble<S>, b: &Aabb<S>) -> bool {
    let mut bits = m.rest_mask;
    while bits != 0 {
        let bit = bits.trailing_zeros() as usize;
        bits &= bits - 1;
        let (axis, up) = (bit / 2, bit % 2 == 1);
        let plane = m.rest_plane[axis];
        if (up && b.max.axis(axis) <= plane) || (!up && b.min.axis(axis) >= plane) {
            return true;
        }
    }
    false
}
