//! Marble–marble contacts in the fixed step (and the event stepper's pair
//! slices): pushed apart, eq. 1 between them, and one more tile pass for a
//! marble its neighbour pushed.

use super::{events, marble_pair, Marble, Scalar, Solver, Vec3, World, T_LOG2};

impl<S: Scalar, const M: usize> World<'_, S, M> {
    /// Marble–marble contacts. A marble pushed by its neighbour gets one more tile
    /// pass from where it stood, so a pair squeezed against a wall never leaves one
    /// of them inside it.
    pub(super) fn collide_marbles<const SPACE: bool>(&mut self) {
        self.stats.pair_runs = self.stats.pair_runs.wrapping_add(1);
        self.collide_pairs(SPACE);
    }

    /// Every pair once, in order, by [`World::collide_pair`]'s code (a marble
    /// out is left out there); `space`: the world has holes (3-D). Returns
    /// whether any pair touched: if none did, no marble changed.
    #[inline]
    pub(super) fn collide_pairs(&mut self, space: bool) -> bool {
        let mut touched = false;
        for a in 0..self.marbles.len() {
            for b in a + 1..self.marbles.len() {
                touched |= self.collide_pair_in(a, b, space);
            }
        }
        touched
    }

    /// One pair of [`World::collide_marbles`]: pushed apart when they overlap, eq. 1
    /// between them, then the tile passes for both. Returns whether they touched.
    #[inline]
    pub(super) fn collide_pair<const SPACE: bool>(&mut self, a: usize, b: usize) -> bool {
        self.collide_pair_in(a, b, SPACE)
    }

    /// [`World::collide_pair`] with the kind of world a value: one copy for both
    /// (the micro:bit v1's flash; the pair is rare, the branch costs nothing).
    #[inline(never)]
    fn collide_pair_in(&mut self, a: usize, b: usize, space: bool) -> bool {
        let p = self.params;
        let r2 = p.radius + p.radius;
        let (ma, mb) = (self.marbles[a], self.marbles[b]);
        if ma.out || mb.out {
            return false;
        }
        let d = mb.pos - ma.pos;
        if d.x.abs() >= r2 || d.y.abs() >= r2 || d.z.abs() >= r2 {
            return false;
        }
        let len2 = d.length_sq();
        if len2 >= r2.times(r2) {
            return false;
        }
        let inv = len2.rsqrt();
        let (n, len) = if inv == S::ZERO {
            (Vec3::new(S::ONE, S::ZERO, S::ZERO), S::ZERO)
        } else {
            (d.scale(inv), len2.times(inv))
        };
        let push = (r2 - len).half();
        let (va, vb, bounce) = marble_pair(
            ma.vel.shr(T_LOG2),
            mb.vel.shr(T_LOG2),
            n,
            p.restitution,
            p.threshold,
        );
        if bounce > S::ZERO {
            self.impacts.record(bounce.shl(T_LOG2));
        }
        let mut na = Marble {
            asleep: false,
            ..ma
        };
        let mut nb = Marble {
            asleep: false,
            ..mb
        };
        na.pos -= n.scale(push);
        nb.pos += n.scale(push);
        let set = |m: &mut Marble<S>, v_step: Vec3<S>| {
            let old = m.vel.dot(n);
            let new = v_step.dot(n).shl(T_LOG2).clamp(-p.v_max, p.v_max);
            m.vel = (m.vel - n.scale(old))
                .sat_add(n.scale(new))
                .clamp_abs(p.v_max);
            if p.events() {
                m.vel = events::cap_speed(m.vel);
            }
        };
        set(&mut na, va);
        set(&mut nb, vb);
        let still = self.solver(Vec3::ZERO, p.k);
        // The passes themselves (what `collide_tiles` comes to), without its
        // inline shortcut for the common case: this one is rare.
        let pushed = (na.pos, nb.pos);
        na.supported = self.passes(space, &mut na, &still, ma.pos) || na.supported;
        nb.supported = self.passes(space, &mut nb, &still, mb.pos) || nb.supported;
        if !p.events() && bounce == S::ZERO {
            self.settle_on(space, &mut na, &mut nb, n, pushed, &still);
        }
        self.marbles[a] = na;
        self.marbles[b] = nb;
        true
    }

    /// Fixed steps, a resting pair (no bounce): when a tile pass took back one
    /// marble's share of the push (a marble on the floor, another on top of it),
    /// the pair overlaps again by that share; the other marble, the one free to
    /// go, takes it (and its tile passes once more). Without this a stack sank
    /// into itself by half a step's pull every step: 14 µm at 1024 steps/s.
    ///
    /// A bounce is left alone: there the overlap is a step's travel, and moving
    /// the marble out of it without its velocity would add energy. The event
    /// stepper's pair slices are short enough for that share to stay under
    /// `2^-12·r`; they are left as they are.
    fn settle_on(
        &mut self,
        space: bool,
        na: &mut Marble<S>,
        nb: &mut Marble<S>,
        n: Vec3<S>,
        (pa, pb): (Vec3<S>, Vec3<S>),
        still: &Solver<S>,
    ) {
        // How far the tile passes moved each marble towards the other, along the
        // pair's normal: at most a tile pass's push-out (`r/4` per axis, checked by
        // the passes), so the products stay in range.
        let towards_b = (na.pos - pa).dot(n);
        let towards_a = (pb - nb.pos).dot(n);
        let closed = towards_b + towards_a;
        if closed <= S::ZERO {
            return;
        }
        if towards_a >= towards_b {
            let from = na.pos;
            na.pos -= n.scale(closed);
            na.supported = self.passes(space, na, still, from) || na.supported;
        } else {
            let from = nb.pos;
            nb.pos += n.scale(closed);
            nb.supported = self.passes(space, nb, still, from) || nb.supported;
        }
    }

    /// The contact passes for either kind of world.
    fn passes(&mut self, space: bool, m: &mut Marble<S>, still: &Solver<S>, from: Vec3<S>) -> bool {
        if space {
            self.contact_passes::<true>(m, still, from)
        } else {
            self.contact_passes::<false>(m, still, from)
        }
    }
}
