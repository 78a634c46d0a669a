//! The contact layer both steppers call: the contact passes against the tiles
//! (the fixed step's, and the event stepper's at the end of a slice), the held
//! faces a resting marble keeps, and one contact's response (eq. 1 through
//! `respond`).
//!
//! Eq. 1 is taken in the board's frame (the tile frame, eq. 4). A marble's
//! velocity there is the board-relative one: a turning board's motion reaches it
//! as the fictitious forces of that frame (`BoardMotion::kick`), and the surface
//! is at rest, `v_b = 0`. The seed's `v_m − v_b` in the world frame is the same
//! vector at the contact, up to `ω × (r·n)`, which lies along the surface and
//! leaves the normal part alone. Subtracting the board's surface velocity from the
//! board-relative velocity as well would count the board's motion twice: a wall
//! swept into a marble would throw it off at `(1 + 2e)` times the wall's speed.

use super::{
    along_normal, candidates, candidates_plane, contact, events, lid_contact, normal_part, resolve,
    Contact, Feature, Impact, Kick, Marble, Outcome, Scalar, Solver, TileIndex, Vec3, World,
    T_LOG2,
};

impl<S: Scalar, const M: usize> World<'_, S, M> {
    /// The contact solver's view of a step of `2^-k` s whose pull adds `dv` (pitch/s)
    /// to the velocity: the acceleration `a·T² = dv · 2^(k−10)` and the step's length
    /// in `T`.
    pub(crate) fn solver(&self, dv: Vec3<S>, k: u32) -> Solver<S> {
        Solver {
            acc: if k >= 2 * T_LOG2 {
                dv.shl(k - 2 * T_LOG2)
            } else {
                dv.shr(2 * T_LOG2 - k)
            },
            dt: S::ONE.shr(k - T_LOG2),
        }
    }

    /// The contact passes of [`World::collide_tiles`].
    #[inline(never)]
    pub(super) fn contact_passes<const SPACE: bool>(
        &mut self,
        m: &mut Marble<S>,
        kick: &Solver<S>,
        start: Vec3<S>,
    ) -> bool {
        let (r, tiles) = (self.params.radius, self.tiles);
        let layout = self.params.layout;
        let mut supported = !SPACE;
        for pass in 0..3 {
            let range = if SPACE {
                candidates(&layout, m.pos, r)
            } else {
                candidates_plane(&layout, m.pos, r)
            };
            let mut touched = false;
            // Face contacts on distinct axes push the marble straight back into the
            // free part of its own cell, where nothing else can be in reach (2r < l):
            // then no further pass is needed. Edges, or two faces on one axis, get one.
            let mut faces = 0u8;
            let mut settled = true;
            // The tiles in reach, then (3-D only) the lid, each asked with the current
            // position (earlier contacts in the pass may have moved the marble). Plain
            // loops: iterator adapters here cost more than the geometry.
            let mut k = range.lo.k;
            while k <= range.hi.k {
                let mut j = range.lo.j;
                while j <= range.hi.j {
                    let mut i = range.lo.i;
                    while i <= range.hi.i {
                        let t = TileIndex::new(i, j, k);
                        if tiles.is_solid(t) {
                            if let Some(c) = contact(m.pos, r, t, &layout.tile_box(t), tiles) {
                                touched = true;
                                settled &= face_once(&mut faces, &c);
                                if self.take_contact::<SPACE>(
                                    m,
                                    &c,
                                    kick,
                                    pass,
                                    start,
                                    &mut supported,
                                ) {
                                    return supported;
                                }
                            }
                        }
                        i += 1;
                    }
                    j += 1;
                }
                k += 1;
            }
            if SPACE {
                if let Some(c) = lid_contact(m.pos, r, self.lid()) {
                    touched = true;
                    settled &= face_once(&mut faces, &c);
                    if self.take_contact::<SPACE>(m, &c, kick, pass, start, &mut supported) {
                        return supported;
                    }
                }
            }
            if !touched || (pass == 0 && settled) {
                break;
            }
        }
        supported
    }

    /// One contact of a pass: resolved in passes 0 and 1; in pass 2, anything still
    /// deeper than the slop (a wedge the passes could not settle) undoes the step.
    /// Returns `true` when the step was undone.
    fn take_contact<const SPACE: bool>(
        &mut self,
        m: &mut Marble<S>,
        c: &Contact<S>,
        kick: &Solver<S>,
        pass: u32,
        start: Vec3<S>,
        supported: &mut bool,
    ) -> bool {
        if pass == 2 {
            if c.depth > self.params.radius.shr(2) {
                m.pos = start;
                m.vel = Vec3::ZERO;
                self.stats.reverts = self.stats.reverts.wrapping_add(1);
                return true;
            }
            return false;
        }
        let outcome = self.apply_contact(m, c, kick);
        if let (Feature::Face(axis), Outcome::Contact) = (c.feature, outcome) {
            let up = c.normal.axis(axis as usize) > S::ZERO;
            m.rest_mask |= 1 << (2 * axis + up as u8);
            m.rest_plane[axis as usize] = c.plane;
        }
        if SPACE && c.normal.y > S::ONE.half() {
            *supported = true;
        }
        false
    }

    /// Keeps a resting marble on the faces it rests on: while it sits exactly on the
    /// face, does not move along its normal, the pull presses it in and the tile is
    /// still there under the contact point, the kick's normal part is dropped. Any of
    /// these failing releases the face (the contact passes take over again). Returns
    /// whether it is held on the floor.
    ///
    /// `backed`: the tiles behind the held faces are known to be there (the
    /// marble's free region says so), and the grid is not asked.
    ///
    /// Inlined into its callers (the flight's acceleration, the fixed step):
    /// out of line, its call and loop took 88 Cortex-M4 instructions a maze
    /// frame; inlined, 23 fewer, and 52 B less of the micro:bit v1's flash.
    #[inline(always)]
    pub(super) fn hold<const SPACE: bool>(
        &self,
        m: &mut Marble<S>,
        kick: &mut Kick<S>,
        backed: bool,
    ) -> bool {
        let r = self.params.radius;
        let mut on_floor = false;
        // The set bits only, lowest first (the same order as a scan of all six: the
        // body clears no bit but its own).
        let mut bits = m.rest_mask;
        while bits != 0 {
            let bit = bits.trailing_zeros() as u8;
            bits &= bits - 1;
            let (axis, up) = ((bit / 2) as usize, bit % 2 == 1);
            let plane = m.rest_plane[axis];
            let at = if up { plane + r } else { plane - r };
            let pull = kick.dv.axis(axis);
            let presses = if up { pull < S::ZERO } else { pull > S::ZERO };
            let mut keep = m.pos.axis(axis) == at && m.vel.axis(axis) == S::ZERO && presses;
            // The region's word is the grid's (debug builds ask the grid too).
            debug_assert!(!backed || self.behind_solid::<SPACE>(m.pos, axis, up, plane));
            if keep && !backed {
                keep = self.behind_solid::<SPACE>(m.pos, axis, up, plane);
            }
            if keep {
                kick.set_axis(axis, (S::ZERO, S::ZERO));
                on_floor |= axis == 1 && up;
            } else {
                m.rest_mask &= !(1 << bit);
            }
        }
        on_floor
    }

    /// Whether the tile behind the contact point of a marble centred at `c` resting
    /// on the face at `plane` (axis `axis`, from above when `up`) is there (the lid,
    /// −y, always is).
    #[inline]
    pub(super) fn behind_solid<const SPACE: bool>(
        &self,
        c: Vec3<S>,
        axis: usize,
        up: bool,
        plane: S,
    ) -> bool {
        if axis == 1 && !up {
            return true;
        }
        let layout = &self.params.layout;
        let behind = if up { plane.next_down() } else { plane };
        // Eq. 6 for the other two axes of the centre (the flat maze's walls are
        // layer 1).
        let j = || if SPACE { layout.index_y(c.y) } else { 1 };
        let t = match axis {
            0 => TileIndex::new(layout.index_xz(behind), j(), layout.index_xz(c.z)),
            1 => TileIndex::new(
                layout.index_xz(c.x),
                layout.index_y(behind),
                layout.index_xz(c.z),
            ),
            _ => TileIndex::new(layout.index_xz(c.x), j(), layout.index_xz(behind)),
        };
        self.tiles.is_solid(t)
    }

    /// Resolves one contact (eq. 1 at the instant of impact, see `respond`).
    fn apply_contact(&mut self, m: &mut Marble<S>, c: &Contact<S>, kick: &Solver<S>) -> Outcome {
        let p = &self.params;
        // A face's or an inside contact's normal is a unit axis
        // (`narrowphase::contact`, `lid_contact`); `normal_part` takes a face's
        // as such.
        let aligned = match c.feature {
            Feature::Face(_) | Feature::Inside => Some(axis_of(c.normal)),
            Feature::Edge => None,
        };
        let face = aligned.filter(|_| matches!(c.feature, Feature::Face(_)));
        debug_assert!(face.is_none_or(|(axis, up)| {
            let mut unit = Vec3::ZERO;
            unit.set_axis(axis, if up { S::ONE } else { -S::ONE });
            c.normal == unit
        }));
        let imp = Impact {
            n: c.normal,
            depth: c.depth,
            v: m.vel.shr(T_LOG2),
            // In the board's frame its surface is at rest (the module doc).
            v_board: Vec3::ZERO,
            acc: kick.acc,
            dt: kick.dt,
            face,
        };
        let res = resolve(&imp, p.restitution, p.threshold);
        match aligned {
            // Axis-aligned: put the centre exactly at `plane ± (r + lift)`.
            Some((axis, up)) => {
                let at = if up {
                    c.plane + p.radius + res.lift
                } else {
                    c.plane - p.radius - res.lift
                };
                match axis {
                    0 => m.pos.x = at,
                    1 => m.pos.y = at,
                    _ => m.pos.z = at,
                }
            }
            None => m.pos += c.normal.scale(res.push),
        }
        let vn_now = normal_part(m.vel, c.normal, face);
        // Under the format's top (127 pitch/s, the event step's limit; fixed steps
        // cap lower): `normal × vn_new` below must fit, and a unit normal times 128
        // does not (it wraps to −128 in release builds; the property
        // `step_survives_arbitrary_states` drives such states).
        let top = p.v_max.min(S::from_int(127));
        let vn_new = res.vn.shl(T_LOG2).clamp(-top, top);
        let mut tangential = m.vel - along_normal(c.normal, vn_now, face);
        if res.deficit > S::ZERO {
            // Pay the rest of the push-out's energy from the tangential speed (rare:
            // a fast marble grazing an edge under a strong pull). In T units: ½|v_t|².
            let vt = tangential.shr(T_LOG2);
            let s2 = vt.length_sq();
            let keep = if s2 > res.deficit + res.deficit {
                S::ONE - (res.deficit + res.deficit).div(s2)
            } else {
                S::ZERO
            };
            tangential = tangential.scale(keep.sqrt());
        }
        // A slanted normal can move speed between axes: keep every axis under the cap
        // (the no-tunnelling bound is per axis). The sum saturates only past the
        // range, at event stepping's speeds, which keeps its magnitude under it.
        m.vel = tangential
            .sat_add(along_normal(c.normal, vn_new, face))
            .clamp_abs(p.v_max);
        if p.events() {
            m.vel = events::cap_speed(m.vel);
        }
        self.stats.contacts = self.stats.contacts.wrapping_add(1);
        if res.outcome == Outcome::Collision {
            self.stats.collisions = self.stats.collisions.wrapping_add(1);
            self.impacts.record(res.impact.shl(T_LOG2));
        }
        res.outcome
    }
}

/// The axis of an axis-aligned unit normal and whether it points up that axis.
fn axis_of<S: Scalar>(n: Vec3<S>) -> (usize, bool) {
    if n.x != S::ZERO {
        (0, n.x > S::ZERO)
    } else if n.y != S::ZERO {
        (1, n.y > S::ZERO)
    } else {
        (2, n.z > S::ZERO)
    }
}

/// Records a face contact's axis in `faces`; `false` for an edge or inside contact,
/// or a second contact on an axis already seen (those need another pass).
fn face_once<S: Scalar>(faces: &mut u8, c: &Contact<S>) -> bool {
    match c.feature {
        Feature::Face(axis) => {
            let bit = 1u8 << axis;
            let fresh = *faces & bit == 0;
            *faces |= bit;
            fresh
        }
        _ => false,
    }
}
