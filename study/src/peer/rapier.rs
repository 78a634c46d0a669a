//! rapier2d (0.36, f32), stepped at the study's rate: a ball collider on box
//! colliders. Its tolerances are scaled with `length_unit` (see
//! [`LENGTH_UNIT`]); CCD as rapier's defaults have it.

use rapier2d::prelude::*;

use marble_rolling::physics::Effects;
use marble_rolling::study::Scene;

use super::{resistance, PeerWorld, Resistance, Setup};

/// Rapier's `length_unit` for a scene in millimetres. Rapier is tuned for
/// metre-sized objects; with 1000 (its literal "units per metre") its slop would
/// be 5 mm, larger than the marble. 1.0 makes its tolerances 5 µm (slop) and
/// 20 µm (prediction): the most accurate setting of those tried (1, 7, 1000).
pub const LENGTH_UNIT: f32 = 1.0;

/// A rapier world set up for a scene.
pub struct Rapier {
    world: PhysicsWorld,
    ball: RigidBodyHandle,
    setup: Setup,
    g_mg: [i32; 3],
    dt: f32,
    mass: f32,
}

impl PeerWorld for Rapier {
    fn new(scene: &Scene, step_log2: u32, effects: Effects) -> Rapier {
        let setup = Setup::new(scene, step_log2, effects);
        let e = setup.restitution;
        let dt = 1.0 / (1u32 << step_log2) as f32;
        let mut world = PhysicsWorld::new();
        world.integration_parameters.dt = dt;
        world.integration_parameters.length_unit = LENGTH_UNIT;
        for (c, h) in &setup.walls {
            world.colliders.insert(
                ColliderBuilder::cuboid(h[0], h[1])
                    .translation(Vector::new(c[0], c[1]))
                    .restitution(e)
                    .friction(0.0),
            );
        }
        let body = RigidBodyBuilder::dynamic()
            .translation(Vector::new(setup.start[0], setup.start[1]))
            .lock_rotations();
        let collider = ColliderBuilder::ball(setup.radius)
            .restitution(e)
            .friction(0.0)
            .density(1.0);
        let (ball, _) = world.insert(body, collider);
        let mass = world.bodies[ball].mass();
        let mut p = Rapier {
            world,
            ball,
            setup,
            g_mg: [0, -1000, 0],
            dt,
            mass,
        };
        p.set_gravity(scene.trace.gravity_mg(0));
        p
    }

    fn steps_per_advance(_step_log2: u32) -> u32 {
        1
    }

    fn gravity_mg(&self) -> [i32; 3] {
        self.g_mg
    }

    fn set_gravity(&mut self, g_mg: [i32; 3]) {
        self.g_mg = g_mg;
        let g = self.setup.gravity(g_mg);
        self.world.gravity = Vector::new(g[0], g[1]);
        self.world.bodies[self.ball].wake_up(true);
    }

    fn advance(&mut self) {
        let g = self.world.gravity;
        // Read through `Index`: a mutable borrow marks the body as changed by
        // the user, and rapier then re-syncs it every step.
        let v = self.world.bodies[self.ball].linvel();
        let (a, hold) = match resistance(self.setup.decel, self.dt, [v.x, v.y], [g.x, g.y]) {
            Resistance::Off => ([0.0; 2], None),
            Resistance::Push(a) => (a, Some(false)),
            Resistance::Hold(a) => (a, Some(true)),
        };
        if let Some(hold) = hold {
            let b = &mut self.world.bodies[self.ball];
            b.reset_forces(false);
            if hold {
                b.set_linvel(Vector::new(0.0, 0.0), false);
            }
            b.add_force(Vector::new(a[0], a[1]) * self.mass, false);
        }
        self.world.step();
    }

    fn state(&mut self) -> ([f64; 2], [f64; 2]) {
        let b = &self.world.bodies[self.ball];
        let (p, v) = (b.translation(), b.linvel());
        ([p.x as f64, p.y as f64], [v.x as f64, v.y as f64])
    }

    fn touching(&mut self) -> bool {
        self.world
            .narrow_phase
            .contact_pairs()
            .any(|p| p.has_any_active_contact())
    }
}
