//! Handling an event: a touch is eq. 1 at that instant or a contact (and, slow
//! against an edge, a slice); a held face's support ends; rolling resistance
//! stops the marble; a slice ends with the fixed step's contact passes.

use super::{
    cap_speed, impact_speed, max_abs, no_faster, Around, Contact, Event, Feature, Flight, Marble,
    Scalar, Segment, Solver, TileIndex, World, EVERY, IDLE_EVENTS, MAX_EVENTS, SLICE_END, T_LOG2,
};

impl<S: Scalar, const M: usize> World<'_, S, M> {
    /// Handles event `ev`, reached after a flight of `s` steps. `space`: the
    /// world has holes (3-D). Out of line and not generic over it: one copy for
    /// both kinds of world, where two (inlined into each `land`) took 1.8 KB of
    /// the micro:bit v1's flash; an event is rare beside the branches it costs.
    #[inline(never)]
    pub(super) fn handle(
        &mut self,
        m: &mut Marble<S>,
        f: &mut Flight<S>,
        s: S,
        ev: Event<S>,
        space: bool,
    ) {
        self.stats.events = self.stats.events.wrapping_add(1);
        f.events += 1;
        if f.events == MAX_EVENTS {
            self.stats.event_limits = self.stats.event_limits.wrapping_add(1);
            f.inelastic = true;
        }
        f.idle = if s == S::ZERO { f.idle + 1 } else { 0 };
        // A slow touch on an edge pivots, unless it is a second contact found
        // inside a pivot slice (two supports: plain slices, passes for both).
        let edge = matches!(ev, Event::Touch(c, _) if c.feature == Feature::Edge)
            && !f.slice.is_some_and(|sl| sl.pivot);
        let slice = match ev {
            Event::Touch(c, t) => self.touch(m, &f.seg, &c, f.inelastic, space).then_some(t),
            Event::Inside(t) => Some(t),
            Event::Release(bit) => {
                m.rest_mask &= !(1 << bit);
                if bit != 3 {
                    None
                } else {
                    m.supported = false;
                    if space {
                        self.rim_under(m)
                    } else {
                        None
                    }
                }
            }
            Event::Stop => {
                self.drag.stopped(&mut m.vel, f.dir, f.holds);
                None
            }
            Event::Later | Event::End | Event::SliceEnd => None,
        };
        // A contact that keeps coming back with no time passing is not a parabola.
        let slice = match (slice, f.idle > IDLE_EVENTS) {
            (None, true) => Some(EVERY),
            (s, _) => s,
        };
        if let Some(t) = slice {
            f.idle = 0;
            f.rail = match (ev, f.slice) {
                (Event::Touch(c, _), Some(sl)) if sl.pivot && c.feature == Feature::Edge => {
                    Some(sl.skip)
                }
                _ => None,
            };
            if f.slice.is_some() {
                // A slice under way ends here (its passes), the new one begins.
                if space {
                    self.end_slice::<true>(m, f);
                } else {
                    self.end_slice::<false>(m, f);
                }
                // Ending a pivot slice turns the velocity to the old edge's
                // tangent, which can point back into the contact just made: a
                // marble over a slot, rolling on one edge, touches the other and
                // would fly the new slice into it at the speed the touch took
                // away (CI, the narrow-corridor property: 1.02·10⁻³ r in).
                if let Event::Touch(c, _) = ev {
                    let vn = m.vel.dot(c.normal);
                    if vn < S::ZERO {
                        m.vel -= c.normal.scale(vn);
                    }
                }
            }
            f.want = Some(t);
            f.around = if edge && t != EVERY {
                Around::Touched
            } else {
                Around::Slice
            };
        }
    }

    /// The tile whose rim a marble is on when its floor's support ends with the
    /// centre still over that tile (closed on every side: on its edge's vertical
    /// plane): its plain slice begins there. The next search would find just that:
    /// the tile's top face touched at once, depth 0, a slow contact the pull
    /// presses in but no solid tile behind it under the centre, so a slice about
    /// the tile; this spares the search (a zero-length flight, about 2.5 k
    /// instructions on the M4, 5 k on the M0: the worst frame of
    /// `maze-2-7x7x2-d9` was Release, that touch, a slice, an edge touch and a
    /// pivot slice). A centre already past the rim (a marble leaving towards
    /// `−x` enters the empty column 1 LSB past it) touches the edge instead,
    /// which pivots: that is left to the search, as is a corner of two solid
    /// tiles (either could be the one touched).
    #[inline(never)]
    fn rim_under(&self, m: &Marble<S>) -> Option<TileIndex> {
        let layout = &self.params.layout;
        let j = layout.index_y(m.rest_plane[1].next_down());
        let lsb = S::lsb();
        // The columns on either side of a centre on a seam (one column elsewhere).
        let xs = [
            layout.index_xz(m.pos.x - lsb),
            layout.index_xz(m.pos.x + lsb),
        ];
        let zs = [
            layout.index_xz(m.pos.z - lsb),
            layout.index_xz(m.pos.z + lsb),
        ];
        let mut found = None;
        for c in 0..4 {
            let t = TileIndex::new(xs[c & 1], j, zs[c >> 1]);
            if self.tiles.is_solid(t) {
                if found.is_some_and(|f| f != t) {
                    return None;
                }
                found = Some(t);
            }
        }
        let t = found?;
        let b = layout.tile_box(t);
        let over = |a: usize| b.min.axis(a) <= m.pos.axis(a) && m.pos.axis(a) <= b.max.axis(a);
        (over(0) && over(2)).then_some(t)
    }

    /// A touch (the marble is at the contact, `seg` the flight that brought it):
    /// eq. 1 at this instant, or a contact. Returns `true` when the marble must go on
    /// in slices (a slow contact with an edge it is pulled against).
    fn touch(
        &mut self,
        m: &mut Marble<S>,
        seg: &Segment<S>,
        c: &Contact<S>,
        inelastic: bool,
        space: bool,
    ) -> bool {
        let p = self.params;
        let e = if inelastic { S::ZERO } else { p.restitution };
        let (k, r, n) = (p.k, p.radius, c.normal);
        self.stats.contacts = self.stats.contacts.wrapping_add(1);
        // Half the approach acceleration (pitch/step²).
        let beta = -n.dot(seg.h);
        // The normal speed at impact from the energy along the normal: for a face
        // from the flight's start to the exact contact plane, where the marble is
        // put; for an edge from where it is, put back on the rounded edge.
        let (w, d) = match c.feature {
            Feature::Face(a) => {
                let a = a as usize;
                let up = n.axis(a) > S::ZERO;
                let at = if up { c.plane + r } else { c.plane - r };
                let d0 = if up {
                    seg.p.axis(a) - at
                } else {
                    at - seg.p.axis(a)
                };
                m.pos.set_axis(a, at);
                (-n.dot(seg.u), d0)
            }
            _ => {
                m.pos += n.scale(c.depth);
                (-n.dot(m.vel.shr(k)), -c.depth)
            }
        };
        let wc = impact_speed(w, beta, d, k);
        let vn = n.dot(m.vel);
        if wc <= p.threshold.shl(T_LOG2) || e == S::ZERO {
            // A contact: no normal speed left (no bounce, no jitter, no Zeno).
            m.vel -= n.scale(vn);
            if beta <= S::ZERO {
                // Not pulled in: it leaves by itself. Off a slanted normal, what
                // rounding leaves of the normal speed could read as a touch again
                // at once: set it a hair off the edge (outwards, with the pull).
                if c.feature == Feature::Edge {
                    let hair = self.tol();
                    m.pos += n.scale(hair + hair);
                }
                return false;
            }
            if let Feature::Face(a) = c.feature {
                let a = a as usize;
                let up = n.axis(a) > S::ZERO;
                let behind = if space {
                    self.behind_solid::<true>(m.pos, a, up, c.plane)
                } else {
                    self.behind_solid::<false>(m.pos, a, up, c.plane)
                };
                if behind {
                    m.rest_mask |= 1 << (2 * a + up as usize);
                    m.rest_plane[a] = c.plane;
                    if space && a == 1 && up {
                        m.supported = true;
                    }
                    return false;
                }
            }
            return true;
        }
        // A bounce. The impact speed is the energy's, and never more than the
        // flight's own.
        let wc = wc.min((-vn).max(S::ZERO));
        let v_c = m.vel - n.scale(vn + wc);
        // Eq. 1, `v' = v − (1 + e)((v − v_b)·n)n`, in the board's frame, where the
        // surface is at rest (`v_b = 0`: the velocity is the board-relative one,
        // see `physics::world::contact`): v_c's normal part is −w_c, so
        // v' = (v_c + w_c·n) + e·w_c·n. A bounce takes no energy in: a slanted
        // normal's rounding (or an approximate root's) must not either.
        let out = m.vel - n.scale(vn) + n.scale(e.times(wc));
        m.vel = no_faster(cap_speed(out), v_c);
        self.stats.collisions = self.stats.collisions.wrapping_add(1);
        self.impacts.record(wc);
        if space && n.y > S::ONE.half() {
            m.supported = false;
        }
        false
    }

    /// A slice's length: `2^-j` of the step, `j ≥ 3` (1/1024 s at 128 steps/s), short
    /// enough that each axis moves at most `r/4` (the fixed step's bound against
    /// tunnelling) and the pull sinks the marble at most `2^-12·r` into what it
    /// rolls around before the passes push it out (inside the `10⁻³·r` clearance the
    /// tests hold everything to).
    pub(super) fn slice_len(&self, seg: &Segment<S>) -> S {
        let r = self.params.radius;
        let (um, hm) = (max_abs(seg.u), max_abs(seg.h));
        let mut len = S::ONE.shr(3);
        let mut j = 3;
        while j < 10 && (um.times(len) > r.shr(2) || hm.times(len.times(len)) > r.shr(SINK)) {
            len = len.half();
            j += 1;
        }
        len
    }

    /// The end of a slice: the fixed step's contact passes, over the slice, from
    /// where it started.
    pub(super) fn end_slice<const SPACE: bool>(&mut self, m: &mut Marble<S>, f: &mut Flight<S>) {
        let Some(sl) = f.slice.take() else {
            return;
        };
        if sl.pivot {
            self.onto_pivot(m, sl.skip);
        }
        if let Some(lo) = sl.on {
            self.onto_marble(m, lo);
        }
        let k = self.params.k;
        let solver = Solver {
            acc: self.solver(f.seg.dv, k).acc,
            dt: (f.t - sl.from).shr(k - T_LOG2),
        };
        let floor = m.rest_mask & (1 << 3) != 0;
        self.charge(SLICE_END);
        let supported = self.contact_passes::<SPACE>(m, &solver, sl.start);
        m.vel = cap_speed(m.vel);
        if SPACE {
            m.supported = supported || floor;
        }
        if sl.pivot {
            // On round the edge while it holds (asked at the next flight).
            f.want = Some(sl.skip);
            f.around = Around::Rolling;
        }
        // On rolling on the sleeping marble while it holds (the next flight).
        f.roll = sl.on;
    }
}

/// A slice sinks the marble at most `2^-SINK·r` into what it rolls round or
/// is pressed on (a plain slice's and a pair slice's bound, `slice_len`,
/// `pair_slice`).
pub(super) const SINK: u32 = 12;

/// The touching tolerance of marbles of radius `r`: a ten-thousandth of it
/// or four LSB (`World::tol`, kept from the world's creation).
pub(in crate::physics::world) fn touch_tolerance<S: Scalar>(r: S) -> S {
    let lsb = S::lsb();
    r.shr(14).max(lsb + lsb + lsb + lsb)
}
