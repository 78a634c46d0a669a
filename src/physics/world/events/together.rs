//! Several marbles that may touch: one timeline for all, every event — a
//! marble's own or a pair's — in time order; a pair pressed together goes on in
//! slices with the fixed step's pair code.

use super::budget::{PAIR_SLICE, PAIR_TEST};
use super::{
    along, bend_of, cap_speed, ended_round, marble_pair, max_abs, quarter, swept_axis, toi_box,
    Aabb, CarriedEdge, Contact, Event, Flight, Marble, Scalar, Segment, Solver, StepObserver, Toi,
    Vec3, World, MAX_EVENTS, T_LOG2,
};

impl<S: Scalar, const M: usize> World<'_, S, M> {
    /// Several marbles that touch each other: one timeline for all, every event —
    /// a marble's own or a pair's — in time order.
    pub(super) fn fly_together<const SPACE: bool, O: StepObserver<S>>(&mut self, obs: &mut O) {
        self.stats.pair_runs = self.stats.pair_runs.wrapping_add(1);
        let count = self.marbles.len();
        let before = self.marbles.clone();
        let mut fl = [Flight::START; M];
        for (n, f) in fl.iter_mut().enumerate().take(count) {
            self.go_on_round(n, f);
        }
        let mut plan: [Option<(S, Event<S>)>; M] = [None; M];
        let mut live = [false; M];
        for (n, alive) in live.iter_mut().enumerate().take(count) {
            let m = self.marbles[n];
            *alive = !m.out;
            if *alive && !m.asleep {
                self.count_runs::<SPACE>(&m);
            }
        }
        let (p, tol) = (self.params, self.tol());
        let r2 = p.radius + p.radius;
        let mut now = S::ZERO;
        let mut rounds = 0u32;
        let mut no_sleep = [false; M];
        // Per pair (`a < b`, at `[a][b]`): the time before which it cannot touch
        // while both marbles fly their present plans; a new plan for either
        // forgets it. Most rounds re-plan one marble, and the pairs without it
        // need no second look (issue 40's item 3: four shaken marbles made six
        // times of impact a round). Two marbles make one pair, which every new
        // plan forgets: there it is not kept.
        let mut apart = [[S::ZERO; M]; M];
        let keep = count > 2;
        loop {
            if self.out_of_flights() {
                self.cut_together(SPACE, &live, &mut fl, &mut no_sleep, now, obs);
                break;
            }
            rounds += 1;
            if rounds > 2 * MAX_EVENTS * (count as u32 + 1) {
                // Out of events: every marble finishes its step on its own, then the
                // fixed step's pair code.
                for n in 0..count {
                    let mut m = self.marbles[n];
                    if !live[n] || m.asleep {
                        continue;
                    }
                    self.stats.event_limits = self.stats.event_limits.wrapping_add(1);
                    fl[n].events = fl[n].events.max(2 * MAX_EVENTS);
                    self.fly_out::<SPACE, O>(n, &mut m, &mut fl[n], obs);
                    self.marbles[n] = m;
                }
                self.collide_marbles::<SPACE>();
                break;
            }
            // Each moving marble's next event of its own.
            for n in 0..count {
                if !live[n] || plan[n].is_some() {
                    continue;
                }
                let mut m = self.marbles[n];
                if m.asleep || fl[n].t >= S::ONE {
                    fl[n].t = if m.asleep { now } else { fl[n].t };
                    fl[n].set_seg(Segment::still(m.pos));
                    plan[n] = Some((S::ONE, Event::End));
                    if keep {
                        forget(&mut apart, n);
                    }
                    continue;
                }
                let (s, ev) = self.next::<SPACE>(n, &mut m, &mut fl[n]);
                self.marbles[n] = m;
                plan[n] = Some((fl[n].after(s), ev));
                if keep {
                    forget(&mut apart, n);
                }
            }
            let mut first: Option<(S, usize)> = None;
            for (n, pl) in plan.iter().enumerate().take(count) {
                if let (true, Some((t, _))) = (live[n], pl) {
                    if first.is_none_or(|(b, _)| *t < b) {
                        first = Some((*t, n));
                    }
                }
            }
            let Some((mut when, mut who)) = first else {
                break;
            };
            // Pairs, each a sphere of radius 2r in its relative motion.
            let mut pair: Option<(usize, usize, Option<Contact<S>>)> = None;
            for a in 0..count {
                for b in a + 1..count {
                    // Two marbles asleep against each other stay so: they fell
                    // asleep because a whole step under this same pull changed
                    // neither, and the step is deterministic. Waking them for their
                    // own contact cost a stacked pair 47 events and 35 slices a
                    // frame, every frame (the drop-onto-marble stress scene:
                    // 370 k instructions a frame at rest).
                    if !live[a] || !live[b] || (self.marbles[a].asleep && self.marbles[b].asleep) {
                        continue;
                    }
                    // Both at the later of their own times (a marble a slice
                    // ahead of the others is checked from where it is).
                    let t0 = now.max(fl[a].t).max(fl[b].t);
                    if t0 >= when || when <= apart[a][b] {
                        continue;
                    }
                    // Over both plans, not only to the round's first event: what
                    // is found past it holds for the rounds after, until either
                    // marble is planned anew. The advance is the same up to
                    // `when`, so this round's answer is too.
                    let until = |n: usize| plan[n].map_or(S::ONE, |(t, _)| t);
                    let horizon = if keep {
                        until(a).min(until(b)) - t0
                    } else {
                        when - t0
                    };
                    let Some(toi) = pair_toi(&fl[a], &fl[b], t0, horizon, r2, tol) else {
                        if keep {
                            apart[a][b] = t0 + horizon;
                        }
                        continue;
                    };
                    self.spend(0, PAIR_TEST);
                    if keep {
                        apart[a][b] = t0
                            + match toi {
                                Toi::Miss => horizon,
                                Toi::Hit { at, .. } | Toi::Inside { at } | Toi::Later(at) => at,
                            };
                    }
                    match toi {
                        Toi::Hit { at, contact, .. }
                            if t0 + at < when || (at == S::ZERO && t0 <= when) =>
                        {
                            when = t0 + at;
                            pair = Some((a, b, Some(contact)));
                        }
                        Toi::Inside { at } if t0 + at <= when => {
                            when = t0 + at;
                            pair = Some((a, b, None));
                        }
                        Toi::Later(at) if t0 + at < when => {
                            // Re-check the pair from there: an event of marble a.
                            when = t0 + at;
                            who = a;
                            pair = None;
                        }
                        _ => {}
                    }
                }
            }
            if pair.is_none() && when >= S::ONE && plan[who].is_some_and(|(_, e)| e == Event::End) {
                // Nothing before the end of the step: everyone flies there.
                for n in 0..count {
                    if live[n] && fl[n].t < S::ONE && !self.marbles[n].asleep {
                        let mut m = self.marbles[n];
                        let s = S::ONE - fl[n].t;
                        let ev = plan[n].map_or(Event::End, |(_, e)| e);
                        self.land::<SPACE, O>(n, &mut m, &mut fl[n], s, ev, obs);
                        self.marbles[n] = m;
                    }
                }
                if (0..count).all(|n| !live[n] || fl[n].t >= S::ONE || self.marbles[n].asleep) {
                    break;
                }
                for pl in plan.iter_mut() {
                    *pl = None;
                }
                continue;
            }
            match pair {
                Some((a, b, contact)) => {
                    for n in [a, b] {
                        let mut m = self.marbles[n];
                        if m.asleep {
                            m.asleep = false;
                            self.count_runs::<SPACE>(&m);
                            fl[n].t = when;
                        } else if when > fl[n].t {
                            let s = when - fl[n].t;
                            self.fly(n, &mut m, &mut fl[n], s, obs);
                        }
                        self.marbles[n] = m;
                        plan[n] = None;
                    }
                    self.stats.events = self.stats.events.wrapping_add(1);
                    let slow = match contact {
                        Some(c) => self.pair_touch(a, b, &c),
                        None => true,
                    };
                    if slow {
                        self.pair_slice::<SPACE, O>(a, b, &mut fl, obs);
                    }
                }
                None => {
                    let n = who;
                    let (t, ev) = plan[n].unwrap_or((when, Event::Later));
                    let (t, ev) = if when < t {
                        (when, Event::Later)
                    } else {
                        (t, ev)
                    };
                    let mut m = self.marbles[n];
                    let s = (t - fl[n].t).max(S::ZERO);
                    self.land::<SPACE, O>(n, &mut m, &mut fl[n], s, ev, obs);
                    self.marbles[n] = m;
                    plan[n] = None;
                }
            }
            now = now.max(when);
        }
        for n in 0..count {
            if !live[n] {
                continue;
            }
            let mut m = self.marbles[n];
            if !SPACE {
                m.supported = true;
            }
            self.check_out::<SPACE>(&mut m);
            if !no_sleep[n] && m != before[n] && self.wedged(n, &m, &before[n]) {
                m.vel = Vec3::ZERO;
            }
            m.asleep = self.sleeping
                && !no_sleep[n]
                && m == before[n]
                && !self.params.spec.effects.board_motion;
            self.pivots[n] = if m.asleep || m.out {
                CarriedEdge::NONE
            } else {
                ended_round(&fl[n])
            };
            self.marbles[n] = m;
        }
    }

    /// The step's budget is spent (`events/budget.rs`) at `now`, the last event:
    /// every marble behind it is flown up to it (no event of its own comes before
    /// its plan, no pair's before `now`), so that the marbles the next step starts
    /// from are where they were at one instant (only a pair a slice ahead is left
    /// ahead). A marble in a slice gets the slice's contact passes there, as at
    /// the slice's end: a slice may sink it up to `2^-12·r` into the tile it
    /// leaves to them. Marks in `no_sleep` those that flew none of the step. Out
    /// of line: the step's own frame stays as small as the v1's stack needs; the
    /// kind of world a value, not a parameter of the type: one copy for both (the
    /// v1's flash).
    #[inline(never)]
    fn cut_together<O: StepObserver<S>>(
        &mut self,
        space: bool,
        live: &[bool; M],
        fl: &mut [Flight<S>; M],
        no_sleep: &mut [bool; M],
        now: S,
        obs: &mut O,
    ) {
        for n in 0..self.marbles.len() {
            let mut m = self.marbles[n];
            if !live[n] || m.asleep || fl[n].t >= S::ONE {
                continue;
            }
            if fl[n].t < now {
                let s = now - fl[n].t;
                self.fly(n, &mut m, &mut fl[n], s, obs);
            }
            if space {
                self.end_slice::<true>(&mut m, &mut fl[n]);
            } else {
                self.end_slice::<false>(&mut m, &mut fl[n]);
            }
            self.marbles[n] = m;
            no_sleep[n] = !self.cut(&fl[n]);
        }
    }

    /// Whether marble `n`, now `m` and `before` at the step's start, is wedged at
    /// rest against another marble: it touches one, moved no more than the touching
    /// tolerance on any axis over the step, and is slower than the restitution
    /// threshold. A marble pressed on a marble and a rim at once is held by both
    /// in turn, slice by slice, and its state never repeats to the bit (it
    /// trembles by a few hundredths of a micrometre, its velocity a few mm/s into
    /// its supports): the exact test, `m == before`, would never put it to sleep,
    /// and the pair would fly plain pair slices for as long as it lies there.
    #[inline(never)]
    fn wedged(&self, n: usize, m: &Marble<S>, before: &Marble<S>) -> bool {
        let (p, tol) = (&self.params, self.tol());
        if max_abs(m.pos - before.pos) > tol || max_abs(m.vel.shr(T_LOG2)) > p.threshold {
            return false;
        }
        let near = p.radius + p.radius + tol;
        self.marbles.iter().enumerate().any(|(o, other)| {
            let d = other.pos - m.pos;
            // Within reach on every axis first: the square of a far separation
            // leaves I8F24's range.
            o != n && !other.out && max_abs(d) <= near && d.length_sq() <= near.times(near)
        })
    }

    /// Two marbles touching (eq. 1 between them, each taking half, as
    /// `collide_marbles` does). Returns `true` when the contact is slow and the pair
    /// must go on in slices.
    fn pair_touch(&mut self, a: usize, b: usize, c: &Contact<S>) -> bool {
        let p = self.params;
        let n = c.normal;
        let (ma, mb) = (self.marbles[a], self.marbles[b]);
        let (va, vb) = (ma.vel.shr(T_LOG2), mb.vel.shr(T_LOG2));
        let approach = -(vb - va).dot(n);
        let (na, nb, bounce) = marble_pair(va, vb, n, p.restitution, p.threshold);
        if bounce > S::ZERO {
            self.impacts.record(bounce.shl(T_LOG2));
        }
        let set = |m: &mut Marble<S>, v: Vec3<S>| {
            let old = m.vel.dot(n);
            let new = n.scale(v.dot(n).shl(T_LOG2).clamp(-p.v_max, p.v_max));
            // The sum can pass the speed limit (a fast marble struck sideways):
            // saturated, then scaled back to it.
            let t = m.vel - n.scale(old);
            m.vel = cap_speed(Vec3::new(
                t.x.sat_add(new.x),
                t.y.sat_add(new.y),
                t.z.sat_add(new.z),
            ));
            m.asleep = false;
        };
        set(&mut self.marbles[a], na);
        set(&mut self.marbles[b], nb);
        approach <= p.threshold
    }

    /// Two marbles pressed together: both fly one slice, then the fixed step's pair
    /// code pushes them apart and runs their tile passes.
    fn pair_slice<const SPACE: bool, O: StepObserver<S>>(
        &mut self,
        a: usize,
        b: usize,
        fl: &mut [Flight<S>; M],
        obs: &mut O,
    ) {
        let p = self.params;
        let r = p.radius;
        let mut len = S::ONE.shr(3);
        for n in [a, b] {
            let mut m = self.marbles[n];
            self.prepare::<SPACE>(n, &mut m, &mut fl[n]);
            self.marbles[n] = m;
            let seg = fl[n].seg;
            let (um, hm) = (max_abs(seg.u), max_abs(seg.h));
            let mut j = 3;
            while j < 10 && (um.times(len) > r.shr(3) || hm.times(len.times(len)) > r.shr(12)) {
                len = len.half();
                j += 1;
            }
            len = len.min(fl[n].len);
        }
        for n in [a, b] {
            let mut m = self.marbles[n];
            let f = &mut fl[n];
            let to = f.after(len);
            obs.flight(n, f.t, to, &f.seg);
            let start = m.pos;
            m.pos = f.seg.pos_at(len);
            m.vel = cap_speed(f.seg.vel_at(len));
            f.t = to;
            let solver = Solver {
                acc: self.solver(f.seg.dv, p.k).acc,
                dt: len.shr(p.k - T_LOG2),
            };
            let floor = m.rest_mask & (1 << 3) != 0;
            let supported = self.contact_passes::<SPACE>(&mut m, &solver, start);
            if SPACE {
                m.supported = supported || floor;
            }
            self.marbles[n] = m;
        }
        self.collide_pair::<SPACE>(a, b);
        for n in [a, b] {
            self.marbles[n].vel = cap_speed(self.marbles[n].vel);
        }
        self.stats.slices = self.stats.slices.wrapping_add(1);
        self.spend(2, PAIR_SLICE);
    }
}

/// Forgets what was known of marble `n`'s pairs (it has a new plan).
#[inline]
fn forget<S: Scalar, const M: usize>(apart: &mut [[S; M]; M], n: usize) {
    for (a, row) in apart.iter_mut().enumerate() {
        if a < n {
            row[n] = S::ZERO;
        } else if a == n {
            *row = [S::ZERO; M];
        }
    }
}

/// The first contact of marbles flying `fa` and `fb`, from `t0` (steps, at or
/// after both flights' starts) over `horizon`: in their relative motion, a
/// sphere of radius `r2` about a point (`toi_box`), or `None` when the pair is
/// out of reach over that horizon. Out of line and with the kind of world out
/// of its type: the timeline has four copies (the two kinds of world, two
/// marbles or more), this code one (the v1's flash).
#[inline(never)]
fn pair_toi<S: Scalar>(
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
    if beyond(&fa.seg, &fb.seg, near + r2.shr(4)) {
        return None;
    }
    let rel = reach(fa, fb, t0, horizon, near)?;
    let point = Aabb {
        min: Vec3::ZERO,
        max: Vec3::ZERO,
    };
    Some(toi_box(&rel, r2, &point, horizon, tol))
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

    /// [`beyond`] never says out of reach where the swept box reaches, and
    /// [`reach`] is the swept box's answer with the relative motion formed for
    /// all axes at once, bit for bit, in the firmware's format: random pairs of
    /// flights (positions a few pitches apart, velocities and pulls up to the
    /// step's bounds, start times and horizons across the step); both
    /// shortcuts are taken for many of them, and many pairs are out of reach
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
    }
}
