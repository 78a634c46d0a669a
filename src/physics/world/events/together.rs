//! Several marbles that may touch: one timeline for all, every event — a
//! marble's own or a pair's — in time order; a pair pressed together goes on in
//! slices with the fixed step's pair code.

use super::budget::{PAIR_SLICE, PAIR_TEST, PAIR_TOI, SEARCH};
use super::pair_test::{far_apart, pair_toi};
use super::touch::SINK;
use super::{
    cap_speed, ended_round, marble_pair, max_abs, CarriedEdge, Contact, Event, Flight, FreeRegion,
    Marble, Scalar, Segment, Solver, StepObserver, Toi, Vec3, World, EVERY, MAX_EVENTS, T_LOG2,
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
                self.cut_together(SPACE, &live, &plan, &mut fl, &mut no_sleep, now, obs);
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
            // Each moving marble's next event of its own. From the second round
            // the budget is checked before each unit of work, not only each
            // round (four marbles' round can search four times and test six
            // pairs); the first round is never cut, so that every marble's step
            // gets somewhere, however small the budget.
            let mut spent = false;
            let check = rounds > 1;
            for n in 0..count {
                if !live[n] || plan[n].is_some() {
                    continue;
                }
                if check && !self.affords(SEARCH) {
                    spent = true;
                    break;
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
                if let Some(lo) = fl[n].roll.map(usize::from) {
                    // Rolling on only while that marble stays still.
                    if !self.stands_still(&fl, lo) {
                        fl[n].roll = None;
                    }
                }
                let (s, ev) = self.next::<SPACE>(n, &mut m, &mut fl[n]);
                self.marbles[n] = m;
                plan[n] = Some((fl[n].after(s), ev));
                if keep {
                    forget(&mut apart, n);
                }
            }
            if spent {
                self.cut_together(SPACE, &live, &plan, &mut fl, &mut no_sleep, now, obs);
                break;
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
            'pairs: for a in 0..count {
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
                    // A marble rolling on a still one, or at rest on it: the slice
                    // keeps them touching, the rest keeps both where they are
                    // (`events/rest.rs`).
                    if self.lies_on(&fl, a, b) || self.lies_on(&fl, b, a) {
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
                    if check && !self.affords(PAIR_TEST + PAIR_TOI) {
                        spent = true;
                        break 'pairs;
                    }
                    self.charge(PAIR_TEST);
                    let Some(toi) = pair_toi(&fl[a], &fl[b], t0, horizon, r2, tol) else {
                        if keep {
                            apart[a][b] = t0 + horizon;
                        }
                        continue;
                    };
                    self.charge(PAIR_TOI);
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
            if spent {
                self.cut_together(SPACE, &live, &plan, &mut fl, &mut no_sleep, now, obs);
                break;
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
                    // A touch on a still marble (`events/rest.rs`; the still one,
                    // asleep or not, is not woken: the same physics either way,
                    // sleeping only skips work): slow, the moving one's next
                    // flight asks whether it rests or rolls there (again only
                    // once it has moved: if neither, the pair goes on as any
                    // pair); faster, a strike on it when what holds it carries
                    // the push.
                    if let Some((up, lo, slow)) = self.lying(&fl, a, b, contact.as_ref(), when) {
                        let mut m = self.marbles[up];
                        if when > fl[up].t {
                            let s = when - fl[up].t;
                            self.fly(up, &mut m, &mut fl[up], s, obs);
                        }
                        let done = slow || self.strike(&mut m, lo);
                        self.marbles[up] = m;
                        if done {
                            if slow {
                                fl[up].roll = Some(lo);
                                fl[up].tried = Some(lo);
                            }
                            plan[up] = None;
                            if keep {
                                forget(&mut apart, up);
                            }
                            self.stats.events = self.stats.events.wrapping_add(1);
                            now = now.max(when);
                            continue;
                        }
                    }
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
                        fl[n].rest = None;
                    }
                    self.stats.events = self.stats.events.wrapping_add(1);
                    let slow = match contact {
                        Some(c) => self.pair_touch(a, b, &c),
                        None => true,
                    };
                    if slow {
                        // The dearest unit (both marbles' searches in it): cut
                        // here, at the touch, when the budget does not cover it.
                        if check && !self.affords(PAIR_SLICE + 2 * SEARCH) {
                            self.cut_together(
                                SPACE,
                                &live,
                                &plan,
                                &mut fl,
                                &mut no_sleep,
                                when,
                                obs,
                            );
                            break;
                        }
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
    /// leaves to them. A marble left ahead and one flown only to `now` were
    /// checked as a pair from the later time, both there, which the cut leaves
    /// one of them short of: they get the fixed step's pair code (pushed apart
    /// if they overlap, eq. 1, the tile passes). Marks in `no_sleep` those that
    /// flew none of the step. Out
    /// of line: the step's own frame stays as small as the v1's stack needs; the
    /// kind of world a value, not a parameter of the type: one copy for both (the
    /// v1's flash).
    #[inline(never)]
    #[allow(clippy::too_many_arguments)]
    fn cut_together<O: StepObserver<S>>(
        &mut self,
        space: bool,
        live: &[bool; M],
        plan: &[Option<(S, Event<S>)>; M],
        fl: &mut [Flight<S>; M],
        no_sleep: &mut [bool; M],
        now: S,
        obs: &mut O,
    ) {
        // A marble whose own plan runs to the step's end with no event (no slice
        // under way) finishes the step when it is out of every other marble's
        // reach over the whole step, by the pair tests' bound without a product
        // (whether the other stops at the cut or not, it stays on its segment):
        // a marble rolling freely is not slowed with a pair pressed together
        // elsewhere on the board (a difficulty-9 maze played at a quarter of its
        // speed for a second). Testing a pair that is within that bound at the
        // cut cost four-shaken's worst frame 13 000 host instructions.
        let (r2, tol) = (self.params.radius + self.params.radius, self.tol());
        let mut goes = [false; M];
        for n in 0..self.marbles.len() {
            goes[n] = live[n]
                && !self.marbles[n].asleep
                && fl[n].t < S::ONE
                && fl[n].slice.is_none()
                && plan[n].is_some_and(|(t, e)| t >= S::ONE && e == Event::End)
                && (0..self.marbles.len())
                    .all(|o| o == n || !live[o] || far_apart(&fl[n], &fl[o], r2, tol));
        }
        for n in 0..self.marbles.len() {
            let mut m = self.marbles[n];
            if !live[n] || m.asleep || fl[n].t >= S::ONE || goes[n] {
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
        for n in (0..self.marbles.len()).filter(|&n| goes[n]) {
            let mut m = self.marbles[n];
            let s = S::ONE - fl[n].t;
            self.fly(n, &mut m, &mut fl[n], s, obs);
            self.marbles[n] = m;
        }
        // Four shaken marbles: one flown to `now` and one a pair slice ahead were
        // left 2.1·10⁻³ pitch into each other (`tests/stress.rs`).
        let (mut at, mut mixed) = (None, false);
        for n in (0..self.marbles.len()).filter(|&n| live[n]) {
            let t = fl[n].t.max(now);
            mixed |= *at.get_or_insert(t) != t;
        }
        if mixed {
            // Twice if any pair touched: a pair pushed apart can push one of
            // them into a third. None touched, nothing moved: the second pass
            // would find the same (four-shaken's cut frames, up to 710 host
            // instructions each).
            if self.collide_pairs(space) {
                self.collide_pairs(space);
            }
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
            while j < 10 && (um.times(len) > r.shr(3) || hm.times(len.times(len)) > r.shr(SINK)) {
                len = len.half();
                j += 1;
            }
            len = len.min(fl[n].len);
        }
        // Each marble's first tile event ends the slice there (a tile it rests
        // against is left to the passes, as in a plain slice): flown past it, a
        // marble struck towards a wall went up to the slice's travel (`r/8`)
        // into it before the passes at the end pushed it out (66 µm in the
        // two-marble level's trace).
        // The search neither asks nor builds the marble's free region: a pair
        // slice's flight, pressed into another marble, is not one a region was
        // built for (with it, the sampled trace's replay of a frame, which starts
        // from the regions the frame ended with, found other events).
        for n in [a, b] {
            let m = self.marbles[n];
            self.charge(SEARCH);
            let region = core::mem::replace(&mut self.free[n], FreeRegion::EMPTY);
            let built = core::mem::replace(&mut fl[n].built, true);
            let (s, _) = self.search::<SPACE>(n, &m, &mut fl[n], len, EVERY, true);
            self.free[n] = region;
            fl[n].built = built;
            // Where the search's limit would put the marble: not where the slice
            // ends (a later flight of that length would take it).
            fl[n].end = None;
            len = len.min(s);
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
