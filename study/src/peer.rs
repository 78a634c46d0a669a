//! The peer: the same scenes in rapier2d (f32), top view, millimetres.
//!
//! A ball collider (the marble's radius) on a fixed set of box colliders built
//! from the level's wall tiles (maximal runs merged, so that a straight wall is
//! one box and the ball never catches an internal edge). Gravity is the tilt's
//! tangential part, scaled by 5/7 when the scene rolls (a 2-D disc cannot roll: the
//! same reduction our engine applies). Restitution `e` on both sides (average
//! rule), friction 0 (our walls are frictionless). With the `friction` effect, the
//! same rolling resistance as ours: a constant force opposing the motion,
//! `c_rr·g·5/7`, and static hold below it. Not modelled: our restitution
//! threshold and our speed cap. Rapier's tolerances are scaled with
//! `length_unit` (see [`LENGTH_UNIT`]); CCD as rapier's defaults have it.

use rapier2d::prelude::*;

use marble_rolling::physics::geometry::grid::Tiles;
use marble_rolling::physics::{Effects, Params, PhysicsSpec, TileIndex};
use marble_rolling::study::{steps, Scene, SceneId, FRAME_LOG2};

use super::host::{energy, time_runs, Outcome, Timing, MM_S2_PER_MG};

/// Rapier's `length_unit` for a scene in millimetres. Rapier is tuned for
/// metre-sized objects; with 1000 (its literal "units per metre") its slop would
/// be 5 mm, larger than the marble. 1.0 makes its tolerances 5 µm (slop) and
/// 20 µm (prediction): the most accurate setting of those tried (1, 7, 1000).
pub const LENGTH_UNIT: f32 = 1.0;

/// A rapier world set up for a scene.
pub struct Peer {
    world: PhysicsWorld,
    ball: RigidBodyHandle,
    g_mg: [i32; 3],
    rolling: bool,
    /// Rolling resistance deceleration (mm/s²), 0 without the friction effect.
    decel: f32,
    dt: f32,
    mass: f32,
}

/// Wall boxes `(x0, z0, x1, z1)` in pitches: maximal horizontal runs of wall
/// tiles, and the tiles left single in their row merged vertically.
fn wall_boxes(tiles: Tiles<'_>, params: &Params<f64>) -> Vec<(f64, f64, f64, f64)> {
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

impl Peer {
    /// The scene at `2^step_log2` steps/s.
    pub fn new(scene: &Scene, step_log2: u32, effects: Effects) -> Peer {
        let spec = PhysicsSpec {
            step_log2,
            effects,
            ..scene.spec
        };
        let params = Params::<f64>::new(spec).expect("valid spec");
        let pitch = params.layout.pitch_um as f64 / 1000.0;
        let e = spec.restitution_milli as f32 / 1000.0;
        let r = (params.radius * pitch) as f32;
        let mut world = PhysicsWorld::new();
        world.integration_parameters.dt = 1.0 / (1u32 << step_log2) as f32;
        world.integration_parameters.length_unit = LENGTH_UNIT;
        for (x0, z0, x1, z1) in wall_boxes(scene.tiles, &params) {
            let (hx, hz) = (
                ((x1 - x0) * pitch / 2.0) as f32,
                ((z1 - z0) * pitch / 2.0) as f32,
            );
            let c = Vector::new(
                ((x0 + x1) * pitch / 2.0) as f32,
                ((z0 + z1) * pitch / 2.0) as f32,
            );
            world.colliders.insert(
                ColliderBuilder::cuboid(hx, hz)
                    .translation(c)
                    .restitution(e)
                    .friction(0.0),
            );
        }
        let (sx, sz) = {
            let (x0, x1) = params.layout.span_xz(scene.start.0 as i32);
            let (z0, z1) = params.layout.span_xz(scene.start.1 as i32);
            ((x0 + x1) / 2.0 * pitch, (z0 + z1) / 2.0 * pitch)
        };
        let body = RigidBodyBuilder::dynamic()
            .translation(Vector::new(sx as f32, sz as f32))
            .lock_rotations();
        let collider = ColliderBuilder::ball(r)
            .restitution(e)
            .friction(0.0)
            .density(1.0);
        let (ball, _) = world.insert(body, collider);
        let mass = world.bodies[ball].mass();
        let decel = if effects.friction {
            (spec.rolling_resistance_ppm as f64 / 1e6
                * 1000.0
                * MM_S2_PER_MG
                * if effects.rolling { 5.0 / 7.0 } else { 1.0 }) as f32
        } else {
            0.0
        };
        let mut p = Peer {
            world,
            ball,
            g_mg: [0, -1000, 0],
            rolling: effects.rolling,
            decel,
            dt: world_dt(step_log2),
            mass,
        };
        p.set_gravity(scene.trace.gravity_mg(0));
        p
    }

    fn set_gravity(&mut self, g: [i32; 3]) {
        self.g_mg = g;
        let c = if self.rolling { 5.0 / 7.0 } else { 1.0 };
        let s = (MM_S2_PER_MG * c) as f32;
        self.world.gravity = Vector::new(g[0] as f32 * s, g[2] as f32 * s);
        self.world.bodies[self.ball].wake_up(true);
    }

    fn step(&mut self) {
        if self.decel > 0.0 {
            let b = &mut self.world.bodies[self.ball];
            let v = b.linvel();
            let speed = v.length();
            b.reset_forces(false);
            if speed > self.decel * self.dt {
                b.add_force(-v / speed * (self.decel * self.mass), false);
            } else if self.world.gravity.length() <= self.decel {
                b.set_linvel(Vector::new(0.0, 0.0), false);
                b.add_force(-self.world.gravity * self.mass, false);
            } else {
                let g = self.world.gravity;
                b.add_force(-g / g.length() * (self.decel * self.mass), false);
            }
        }
        self.world.step();
    }

    /// Ball position and velocity (mm, mm/s).
    pub fn state(&self) -> ([f64; 2], [f64; 2]) {
        let b = &self.world.bodies[self.ball];
        let (p, v) = (b.translation(), b.linvel());
        ([p.x as f64, p.y as f64], [v.x as f64, v.y as f64])
    }

    fn touching(&self) -> bool {
        self.world
            .narrow_phase
            .contact_pairs()
            .any(|p| p.has_any_active_contact())
    }
}

fn world_dt(step_log2: u32) -> f32 {
    1.0 / (1u32 << step_log2) as f32
}

/// Steps `peer` from step `from` to `to` with the scene's tilt trace.
fn drive(
    peer: &mut Peer,
    scene: &Scene,
    step_log2: u32,
    from: u32,
    to: u32,
    mut each: impl FnMut(&Peer, u32),
) {
    let sub = step_log2.saturating_sub(FRAME_LOG2);
    let mask = (1u32 << sub) - 1;
    for n in from..to {
        if n & mask == 0 {
            let g = scene.trace.gravity_mg(n >> sub);
            if g != peer.g_mg {
                peer.set_gravity(g);
            }
        }
        peer.step();
        each(peer, n + 1);
    }
}

/// The whole scene, unobserved (what is timed and what callgrind counts).
#[inline(never)]
pub fn run_plain(peer: &mut Peer, scene: &Scene, step_log2: u32) {
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

/// An instrumented rapier run.
pub fn measure(id: SceneId, step_log2: u32) -> Outcome {
    let scene = Scene::get(id);
    let effects = scene.spec.effects;
    let params = Params::<f64>::new(PhysicsSpec {
        step_log2,
        ..scene.spec
    })
    .expect("valid spec");
    let mut peer = Peer::new(&scene, step_log2, effects);
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
    out.energy_end = energy(rolling, peer.g_mg, pos, v).0;
    out.max_pen_um = worst.max(0.0) * 1000.0;
    out.contacts = contact_steps;
    out.collisions = bounces;
    out.steps = steps(step_log2);
    out
}

/// Host time per rapier step.
pub fn time(id: SceneId, step_log2: u32, reps: usize, min_total_s: f64) -> Timing {
    let scene = Scene::get(id);
    let effects = scene.spec.effects;
    time_runs(
        steps(step_log2),
        reps,
        min_total_s,
        || Peer::new(&scene, step_log2, effects),
        |p| run_plain(p, &scene, step_log2),
    )
}

/// One plain rapier run (for callgrind).
pub fn plain(id: SceneId, step_log2: u32) -> [f64; 2] {
    let scene = Scene::get(id);
    let mut p = Peer::new(&scene, step_log2, scene.spec.effects);
    run_plain(&mut p, &scene, step_log2);
    p.state().0
}
