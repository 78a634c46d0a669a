//! The fixed stepper ([`Stepping::Fixed`]): integrate over a step bounded so
//! that nothing can tunnel, then the contact passes (`contact.rs`) push the
//! marble out of whatever it reached. The study's baseline.
//!
//! **No tunnelling, by a step bound.** Each axis of the velocity is capped at
//! `v_max = min(r/4 per step, 64 pitch/s)` and each axis of the kick's displacement
//! `½·a·dt²` at `r/8`, so the centre moves at most `3r/8` per axis and `0.65·r`
//! overall in one step. The contact passes leave the centre at
//! least `r − r/4` from every solid box, and a step whose end state still overlaps
//! deeper than that is undone (`StepStats::reverts`). So the centre can never enter
//! a tile, let alone cross one, however thin the tile and whatever the step. At the
//! default 1024 steps/s and a 3.5 mm marble in a 12 mm pitch the cap is 64 pitch/s
//! (0.77 m/s), well above what a tilted toy reaches in one cell.

use super::{
    advance, advance_plane, candidates, candidates_plane, lid_contact, out_of_reach, Kick, Marble,
    Scalar, TileIndex, Vec3, World,
};

impl<S: Scalar, const M: usize> World<'_, S, M> {
    pub(super) fn step_fixed(&mut self) {
        self.stats.steps = self.stats.steps.wrapping_add(1);
        if self.params.spec.effects.holes {
            self.step_marbles::<true>();
        } else {
            self.step_marbles::<false>();
        }
        if self.params.spec.effects.marbles && self.marbles.len() > 1 {
            if self.params.spec.effects.holes {
                self.collide_marbles::<true>();
            } else {
                self.collide_marbles::<false>();
            }
        }
    }

    fn step_marbles<const SPACE: bool>(&mut self) {
        for n in 0..self.marbles.len() {
            let mut m = self.marbles[n];
            if !m.out && !m.asleep {
                self.step_marble::<SPACE>(n, &mut m);
                // Asleep only when the step changed nothing at all and the board
                // is not turning (its pull then changes every step). The step
                // works on the copy: the stored marble is still the one before it.
                m.asleep =
                    self.sleeping && m == self.marbles[n] && !self.params.spec.effects.board_motion;
                self.marbles[n] = m;
            }
        }
    }

    fn step_marble<const SPACE: bool>(&mut self, n: usize, m: &mut Marble<S>) {
        let k = self.params.k;
        let effects = self.params.spec.effects;
        let supported = !SPACE || m.supported;
        let mut kick = if supported {
            self.kick_roll
        } else {
            self.kick_free
        };
        if effects.friction && supported {
            self.stats.friction_runs = self.stats.friction_runs.wrapping_add(1);
            self.drag.apply(&mut m.vel, &mut kick);
        }
        if effects.board_motion {
            self.stats.board_motion_runs = self.stats.board_motion_runs.wrapping_add(1);
            let mut extra = self.motion.kick(m.pos, m.vel.shr(k), k);
            // A violently jerked board can ask for more than the speed range holds.
            extra.dv = extra.dv.clamp_abs(self.params.v_max);
            if !SPACE {
                extra.dv.y = S::ZERO;
                extra.dp.y = S::ZERO;
            }
            kick = kick.plus(extra).clamped(self.params.radius.shr(3));
        }
        let mut held_on_floor = false;
        if m.rest_mask != 0 {
            held_on_floor = self.hold::<SPACE>(m, &mut kick, false);
        }
        let start = m.pos;
        if SPACE {
            self.stats.space_runs = self.stats.space_runs.wrapping_add(1);
            advance(&mut m.pos, &mut m.vel, &kick, k);
        } else {
            advance_plane(&mut m.pos, &mut m.vel, &kick, k);
        }
        m.vel = m.vel.clamp_abs(self.params.v_max);
        m.supported = self.collide_tiles::<SPACE>(n, m, &kick, start) || held_on_floor;
        self.check_out::<SPACE>(m);
    }

    /// Contact passes against the tiles (and, in 3-D, the lid) for marble number
    /// `n`; returns whether the floor supports the marble.
    ///
    /// Nearly every step has no solid tile in reach at all (a marble on the floor
    /// reaches only the wall layer; one held on a floor or on a face it rests
    /// against from +x'/+z' has that tile just outside its reach), and then the
    /// passes end after the first with nothing touched: what they return is known
    /// without them. That case is checked here, inline and with no contact code (and
    /// without even the tile lookups when the candidates are the ones last found
    /// free); the passes run only when a solid tile (or the lid) is within a radius
    /// of the centre on every axis.
    #[inline(always)]
    pub(super) fn collide_tiles<const SPACE: bool>(
        &mut self,
        n: usize,
        m: &mut Marble<S>,
        kick: &Kick<S>,
        start: Vec3<S>,
    ) -> bool {
        let (r, tiles, layout) = (self.params.radius, self.tiles, &self.params.layout);
        let range = if SPACE {
            candidates(layout, m.pos, r)
        } else {
            candidates_plane(layout, m.pos, r)
        };
        let mut clear = range == self.clear[n];
        if !clear {
            clear = true;
            // No solid tile at all: the range is free wherever the marble is in it.
            let mut empty = true;
            let mut k = range.lo.k;
            while clear && k <= range.hi.k {
                let mut j = range.lo.j;
                while clear && j <= range.hi.j {
                    let mut i = range.lo.i;
                    while clear && i <= range.hi.i {
                        let t = TileIndex::new(i, j, k);
                        if tiles.is_solid(t) {
                            // A solid tile a whole radius away along some axis is not
                            // touched either: the first pass would find no contact
                            // with it (`contact`'s first test, the same comparisons).
                            // That is a marble resting on a face it touches from −x'/−z'
                            // (the face's plane is the tile's lower bound, in reach),
                            // or passing a post diagonally. Not cached: it depends on
                            // where the marble is.
                            // (A floor tile in reach, in 3-D, is a marble sinking into
                            // it: a contact, not worth the test.)
                            empty = false;
                            clear = j >= 1 && out_of_reach(m.pos, r, &layout.tile_box(t));
                        }
                        i += 1;
                    }
                    j += 1;
                }
                k += 1;
            }
            if empty {
                self.clear[n] = range;
            }
        }
        if clear && (!SPACE || lid_contact(m.pos, r, self.lid()).is_none()) {
            // What the passes return when the first touches nothing.
            return !SPACE;
        }
        let solver = self.solver(kick.dv, self.params.k);
        self.contact_passes::<SPACE>(m, &solver, start)
    }
}
