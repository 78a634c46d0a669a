//! The peers: the same scenes in two established engines, rapier2d ([`rapier`])
//! and Box2D v3 ([`box2d`]), top view, millimetres, f32.
//!
//! Both model the marble the same way, so that their differences are the
//! engines': a disc on fixed boxes built from the level's wall tiles (maximal runs
//! merged, so that a straight wall is one box and the disc never catches an
//! internal edge), its rotation locked; gravity is the tilt's tangential part,
//! scaled by 5/7 when the scene rolls (a 2-D disc cannot roll: the same reduction
//! our engine applies); restitution `e`, frictionless walls. With the `friction`
//! effect, the same rolling resistance as ours: a constant force opposing the
//! motion, `c_rr·g·5/7`, and static hold below it ([`resistance`]). Not
//! modelled: our restitution threshold and our speed cap.
//!
//! Everything measured about a peer run ([`measure`], [`time`], [`plain`]) is
//! shared, so both are judged by the same yardstick as ours.

pub mod box2d;
pub mod rapier;

use marble_rolling::physics::geometry::grid::Tiles;
use marble_rolling::physics::{Effects, Params, PhysicsSpec, TileIndex};
use marble_rolling::study::{steps, Scene, SceneId, FRAME_LOG2};

use super::host::{energy, time_runs, Outcome, Timing, MM_S2_PER_MG};

/// A peer engine's world set up for one scene.
pub trait PeerWorld: Sized {
    /// The scene at `2^step_log2` steps/s (substeps, for an engine that
    /// substeps inside its own step).
    fn new(scene: &Scene, step_log2: u32, effects: Effects) -> Self;
    /// How many of the study's steps one [`PeerWorld::advance`] covers at
    /// `2^step_log2` steps/s: 1 for an engine stepped at that rate, the
    /// substeps per frame for one stepped once a frame.
    fn steps_per_advance(step_log2: u32) -> u32;
    /// The tilt now in force (mg).
    fn gravity_mg(&self) -> [i32; 3];
    /// A new tilt (mg), waking the marble.
    fn set_gravity(&mut self, g_mg: [i32; 3]);
    /// One step of the engine.
    fn advance(&mut self);
    /// Marble position and velocity (mm, mm/s).
    fn state(&mut self) -> ([f64; 2], [f64; 2]);
    /// Whether the marble touches a wall now.
    fn touching(&mut self) -> bool;
}

/// Wall boxes `(x0, z0, x1, z1)` in pitches: maximal horizontal runs of wall
/// tiles, and the tiles left single in their row merged vertically.
pub fn wall_boxes(tiles: Tiles<'_>, params: &Params<f64>) -> Vec<(f64, f64, f64, f64)> {
    let (nx, nz) = (tiles.nx() as i32, tiles.nz() as i32);
    let solid = |i: i32, k: i32| tiles.is_solid(TileIndex::new(i, 1, k));
    let mut used = vec![false; (nx * nz) as usize];
    let idx = |i: i32, k: i32| (k * nx + i) as usize;
    let mut boxes = Vec::new();
    for k in 0..nz {
        for i in 0..nx {
            if used[idx(i, k)] || !solid(i, k) {
                continue;
            }
            let mut i1 = i;
            while i1 + 1 < nx && solid(i1 + 1, k) && !used[idx(i1 + 1, k)] {
                i1 += 1;
            }
            let mut k1 = k;
            if i1 == i {
                while k1 + 1 < nz && solid(i, k1 + 1) && !used[idx(i, k1 + 1)] {
                    let right = i + 1 < nx && solid(i + 1, k1 + 1);
                    let left = i > 0 && solid(i - 1, k1 + 1);
                    if left || right {
                        // That tile starts or ends a horizontal run: leave it to it.
                        break;
                    }
                    k1 += 1;
                }
            }
            for kk in k..=k1 {
                for ii in i..=i1 {
                    used[idx(ii, kk)] = true;
                }
            }
            let (x0, _) = params.layout.span_xz(i);
            let (_, x1) = params.layout.span_xz(i1);
            let (z0, _) = params.layout.span_xz(k);
            let (_, z1) = params.layout.span_xz(k1);
            boxes.push((x0, z0, x1, z1));
        }
    }
    boxes
}

/// What a peer's scene is made of, in its units (mm, mm/s², f32).
pub struct Setup {
    /// Wall boxes: centre and half extents, mm.
    pub walls: Vec<([f32; 2], [f32; 2])>,
    /// The marble's start (mm) and radius (mm).
    pub start: [f32; 2],
    /// Radius, mm.
    pub radius: f32,
    /// Restitution.
    pub restitution: f32,
    /// Rolling resistance deceleration (mm/s²), 0 without the friction effect.
    pub decel: f32,
    /// Whether the marble rolls (gravity × 5/7).
    pub rolling: bool,
}

impl Setup {
    /// The scene's walls, marble and material at `2^step_log2` steps/s.
    pub fn new(scene: &Scene, step_log2: u32, effects: Effects) -> Setup {
        let spec = PhysicsSpec {
            step_log2,
            effects,
            ..scene.spec
        };
        let params = Params::<f64>::new(spec).expect("valid spec");
        let pitch = params.layout.pitch_um as f64 / 1000.0;
        let walls = wall_boxes(scene.tiles, &params)
            .into_iter()
            .map(|(x0, z0, x1, z1)| {
                (
                    [
                        ((x0 + x1) * pitch / 2.0) as f32,
                        ((z0 + z1) * pitch / 2.0) as f32,
                    ],
                    [
                        ((x1 - x0) * pitch / 2.0) as f32,
                        ((z1 - z0) * pitch / 2.0) as f32,
                    ],
                )
            })
            .collect();
        let (x0, x1) = params.layout.span_xz(scene.start.0 as i32);
        let (z0, z1) = params.layout.span_xz(scene.start.1 as i32);
        let decel = if effects.friction {
            (spec.rolling_resistance_ppm as f64 / 1e6
                * 1000.0
                * MM_S2_PER_MG
                * if effects.rolling { 5.0 / 7.0 } else { 1.0 }) as f32
        } else {
            0.0
        };
        Setup {
            walls,
            start: [
                ((x0 + x1) / 2.0 * pitch) as f32,
                ((z0 + z1) / 2.0 * pitch) as f32,
            ],
            radius: (params.radius * pitch) as f32,
            restitution: spec.restitution_milli as f32 / 1000.0,
            decel,
            rolling: effects.rolling,
        }
    }

    /// The tangential acceleration of a tilt (mm/s²), reduced to 5/7 when the
    /// marble rolls.
    pub fn gravity(&self, g_mg: [i32; 3]) -> [f32; 2] {
        let c = if self.rolling { 5.0 / 7.0 } else { 1.0 };
        let s = (MM_S2_PER_MG * c) as f32;
        [g_mg[0] as f32 * s, g_mg[2] as f32 * s]
    }
}

/// Rolling resistance over the next `dt` seconds, per unit mass.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Resistance {
    /// None (the friction effect is off).
    Off,
    /// A force per unit mass (mm/s²): against the motion, or, at rest on a tilt
    /// steeper than the resistance, against gravity.
    Push([f32; 2]),
    /// Static hold: the marble stops and the push cancels gravity.
    Hold([f32; 2]),
}

/// The rolling resistance for velocity `v` (mm/s) under gravity `g` (mm/s²):
/// `decel` (mm/s²) against the motion while the marble would not stop within
/// `dt`; once it would, it holds if the tilt is no steeper than `decel`.
pub fn resistance(decel: f32, dt: f32, v: [f32; 2], g: [f32; 2]) -> Resistance {
    if decel <= 0.0 {
        return Resistance::Off;
    }
    let speed = (v[0] * v[0] + v[1] * v[1]).sqrt();
    let pull = (g[0] * g[0] + g[1] * g[1]).sqrt();
    if speed > decel * dt {
        Resistance::Push([-v[0] / speed * decel, -v[1] / speed * decel])
    } else if pull <= decel {
        Resistance::Hold([-g[0], -g[1]])
    } else {
        Resistance::Push([-g[0] / pull * decel, -g[1] / pull * decel])
    }
}

/// Steps `peer` from step `from` to `to` with the scene's tilt trace, calling
/// `each` after every advance with the number of steps done.
fn drive<P: PeerWorld>(
    peer: &mut P,
    scene: &Scene,
    step_log2: u32,
    from: u32,
    to: u32,
    mut each: impl FnMut(&mut P, u32),
) {
    let sub = step_log2.saturating_sub(FRAME_LOG2);
    let per = P::steps_per_advance(step_log2).max(1);
    let mut n = from;
    while n < to {
        if n & ((1u32 << sub) - 1) == 0 {
            let g = scene.trace.gravity_mg(n >> sub);
            if g != peer.gravity_mg() {
                peer.set_gravity(g);
            }
        }
        peer.advance();
        n += per;
        each(peer, n);
    }
}

/// The whole scene, unobserved (what is timed and what callgrind counts).
#[inline(never)]
pub fn run_plain<P: PeerWorld>(peer: &mut P, scene: &Scene, step_log2: u32) {
    drive(peer, scene, step_log2, 0, steps(step_log2), |_, _| {});
}

/// The deepest overlap (mm, negative: clear) of a disc at `c` (mm) with the
/// scene's wall tiles.
fn overlap_mm(scene: &Scene, params: &Params<f64>, c: [f64; 2]) -> f64 {
    let pitch = params.layout.pitch_um as f64 / 1000.0;
    let r = params.radius * pitch;
    let (x, z) = (c[0] / pitch, c[1] / pitch);
    let rr = params.radius;
    let (i0, i1) = (
        params.layout.index_xz(x - rr) - 1,
        params.layout.index_xz(x + rr) + 1,
    );
    let (k0, k1) = (
        params.layout.index_xz(z - rr) - 1,
        params.layout.index_xz(z + rr) + 1,
    );
    let mut best = f64::INFINITY;
    for k in k0..=k1 {
        for i in i0..=i1 {
            let t = TileIndex::new(i, 1, k);
            if !scene.tiles.is_solid(t) {
                continue;
            }
            let b = params.layout.tile_box(t);
            let dx = if x < b.min.x {
                b.min.x - x
            } else if x > b.max.x {
                x - b.max.x
            } else {
                0.0
            };
            let dz = if z < b.min.z {
                b.min.z - z
            } else if z > b.max.z {
                z - b.max.z
            } else {
                0.0
            };
            best = best.min((dx * dx + dz * dz).sqrt() * pitch);
        }
    }
    r - best
}

/// An instrumented peer run. Overlap, contacts and bounces are sampled after
/// every [`PeerWorld::advance`]: every step of an engine stepped at the rate,
/// every frame of one that substeps inside its step.
pub fn measure<P: PeerWorld>(id: SceneId, step_log2: u32) -> Outcome {
    let scene = Scene::get(id);
    let effects = scene.spec.effects;
    let params = Params::<f64>::new(PhysicsSpec {
        step_log2,
        ..scene.spec
    })
    .expect("valid spec");
    let mut peer = P::new(&scene, step_log2, effects);
    let one = 1u32 << step_log2;
    let mut out = Outcome::default();
    let mut worst = f64::NEG_INFINITY;
    let mut contact_steps = 0u64;
    let mut bounces = 0u64;
    let mut last_v = [0.0f64; 2];
    let rolling = effects.rolling;
    let (ex, ez) = {
        let (nx, nz) = (scene.tiles.nx() as i32, scene.tiles.nz() as i32);
        let pitch = params.layout.pitch_um as f64 / 1000.0;
        (
            params.layout.span_xz(nx - 1).1 * pitch,
            params.layout.span_xz(nz - 1).1 * pitch,
        )
    };
    let frame_mask = (1u32 << (step_log2 - FRAME_LOG2)) - 1;
    out.track.push(peer.state().0);
    drive(&mut peer, &scene, step_log2, 0, steps(step_log2), |p, n| {
        let (pos, v) = p.state();
        if n & frame_mask == 0 {
            out.track.push(pos);
        }
        worst = worst.max(overlap_mm(&scene, &params, pos));
        if p.touching() {
            contact_steps += 1;
            // A bounce: a velocity component reversed by a contact.
            if (0..2).any(|a| last_v[a] * v[a] < 0.0 && (v[a] - last_v[a]).abs() > 20.0) {
                bounces += 1;
            }
        }
        last_v = v;
        let ke = 0.5 * if rolling { 1.4 } else { 1.0 } * (v[0] * v[0] + v[1] * v[1]);
        out.ke_max = out.ke_max.max(ke);
        if n == one {
            out.pos1 = pos;
        }
        if pos[0] < 0.0 || pos[1] < 0.0 || pos[0] > ex || pos[1] > ez {
            out.out = true;
        }
    });
    let (pos, v) = peer.state();
    out.pos10 = pos;
    out.energy_end = energy(rolling, peer.gravity_mg(), pos, v).0;
    out.max_pen_um = worst.max(0.0) * 1000.0;
    out.contacts = contact_steps;
    out.collisions = bounces;
    out.steps = steps(step_log2);
    out
}

/// Host time per study step (a substep, for an engine that substeps).
pub fn time<P: PeerWorld>(id: SceneId, step_log2: u32, reps: usize, min_total_s: f64) -> Timing {
    let scene = Scene::get(id);
    let effects = scene.spec.effects;
    time_runs(
        steps(step_log2),
        reps,
        min_total_s,
        || P::new(&scene, step_log2, effects),
        |p| run_plain(p, &scene, step_log2),
    )
}

/// One plain run (for callgrind): the end position.
pub fn plain<P: PeerWorld>(id: SceneId, step_log2: u32) -> [f64; 2] {
    let scene = Scene::get(id);
    let mut p = P::new(&scene, step_log2, scene.spec.effects);
    run_plain(&mut p, &scene, step_log2);
    p.state().0
}
