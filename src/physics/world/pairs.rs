//! Marble–marble contacts in the fixed step (and the event stepper's pair
//! slices): pushed apart, eq. 1 between them, and one more tile pass for a
//! marble its neighbour pushed.

use super::*;

impl<S: Scalar, const M: usize> World<'_, S, M> {
    /// Marble–marble contacts. A marble pushed by its neighbour gets one more tile
    /// pass from where it stood, so a pair squeezed against a wall never leaves one
    /// of them inside it.
    pub(super) fn collide_marbles<const SPACE: bool>(&mut self) {
        self.stats.pair_runs = self.stats.pair_runs.wrapping_add(1);
        for a in 0..self.marbles.len() {
            for b in a + 1..self.marbles.len() {
                self.collide_pair::<SPACE>(a, b);
            }
        }
    }

    /// One pair of [`World::collide_marbles`]: pushed apart when they overlap, eq. 1
    /// between them, then the tile passes for both. Returns whether they touched.
    pub(super) fn collide_pair<const SPACE: bool>(&mut self, a: usize, b: usize) -> bool {
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
        if len2 >= r2 * r2 {
            return false;
        }
        let inv = len2.rsqrt();
        let (n, len) = if inv == S::ZERO {
            (Vec3::new(S::ONE, S::ZERO, S::ZERO), S::ZERO)
        } else {
            (d.scale(inv), len2 * inv)
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
        na.supported = self.contact_passes::<SPACE>(&mut na, &still, ma.pos) || na.supported;
        nb.supported = self.contact_passes::<SPACE>(&mut nb, &still, mb.pos) || nb.supported;
        self.marbles[a] = na;
        self.marbles[b] = nb;
        true
    }
}
