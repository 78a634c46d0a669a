//! Box2D v3 through the `boxdd` crate (f32), the engine the field holds up:
//! stepped once per 128 Hz frame with `2^(k − 7)` substeps for the study's
//! `2^k` steps/s (Box2D's soft-step solver substeps inside `b2World_Step`; its
//! recommended setting is 4 substeps, 512 steps/s here). A circle on box
//! polygons, one static body per wall box, its rotation locked. Box2D's
//! tolerances follow its length unit: 1 mm of the study is 0.1 m to it
//! ([`LENGTH_UNITS_PER_METRE`]), so a 3.5 mm marble is the 0.35 m ball its
//! defaults are tuned for (linear slop 0.05 mm, restitution threshold 10 mm/s,
//! sleep below 0.5 mm/s). Everything else is its defaults: continuous collision,
//! soft contacts, sleeping.

use std::sync::OnceLock;

use boxdd::{
    shapes, BodyId, BodyType, Foundation, FoundationConfig, MotionLocks, Position, ShapeDef,
    SurfaceMaterial, Vec2, World,
};

use marble_rolling::physics::Effects;
use marble_rolling::study::{Scene, FRAME_LOG2};

use super::{resistance, PeerWorld, Resistance, Setup};

/// The study's millimetres per Box2D metre: 1 mm = 0.1 m.
pub const LENGTH_UNITS_PER_METRE: f32 = 10.0;

/// Box2D's process-wide setup (its length unit is a global of the C library).
fn foundation() -> &'static Foundation {
    static ROOT: OnceLock<&'static Foundation> = OnceLock::new();
    ROOT.get_or_init(|| {
        Foundation::initialize(FoundationConfig::new(LENGTH_UNITS_PER_METRE))
            .expect("Box2D foundation with 10 length units per metre")
    })
}

/// The Box2D version the crate builds, e.g. `3.2.0`.
pub fn version() -> String {
    foundation();
    match boxdd::version() {
        Ok(v) => format!("{}.{}.{}", v.major, v.minor, v.revision),
        Err(e) => format!("unknown ({e})"),
    }
}

/// A Box2D world set up for a scene.
pub struct Box2d {
    world: World,
    ball: BodyId,
    setup: Setup,
    g_mg: [i32; 3],
    substeps: i32,
    mass: f32,
}

const FRAME_S: f32 = 1.0 / (1u32 << FRAME_LOG2) as f32;

impl PeerWorld for Box2d {
    fn new(scene: &Scene, step_log2: u32, effects: Effects) -> Box2d {
        let root = foundation();
        let setup = Setup::new(scene, step_log2, effects);
        let def = root
            .world_builder()
            .gravity(Vec2::new(0.0, 0.0))
            .build()
            .expect("Box2D world definition");
        let mut world = root.create_world(def).expect("Box2D world");
        let material = SurfaceMaterial::new()
            .with_friction(0.0)
            .and_then(|m| m.with_restitution(setup.restitution))
            .expect("Box2D surface material");
        let shape = ShapeDef::builder()
            .material(material)
            .density(1.0)
            .build()
            .expect("Box2D shape definition");
        for (c, h) in &setup.walls {
            let def = root
                .body_builder()
                .body_type(BodyType::Static)
                .position(Position::from([c[0], c[1]]))
                .build()
                .expect("Box2D wall body");
            let wall = world.create_body(def).expect("Box2D wall body");
            let polygon = shapes::box_polygon(h[0], h[1]).expect("Box2D wall box");
            world
                .body(wall)
                .and_then(|mut b| b.create_polygon(&shape, &polygon))
                .expect("Box2D wall shape");
        }
        let def = root
            .body_builder()
            .body_type(BodyType::Dynamic)
            .position(Position::from(setup.start))
            .motion_locks(MotionLocks::new(false, false, true))
            .build()
            .expect("Box2D marble body");
        let ball = world.create_body(def).expect("Box2D marble body");
        let circle = shapes::circle(Vec2::new(0.0, 0.0), setup.radius).expect("Box2D marble disc");
        let mass = world
            .body(ball)
            .and_then(|mut b| {
                b.create_circle(&shape, &circle)?;
                b.mass()
            })
            .expect("Box2D marble shape");
        let mut p = Box2d {
            world,
            ball,
            setup,
            g_mg: [0, -1000, 0],
            substeps: 1 << step_log2.saturating_sub(FRAME_LOG2),
            mass,
        };
        p.set_gravity(scene.trace.gravity_mg(0));
        p
    }

    fn steps_per_advance(step_log2: u32) -> u32 {
        1 << step_log2.saturating_sub(FRAME_LOG2)
    }

    fn gravity_mg(&self) -> [i32; 3] {
        self.g_mg
    }

    fn set_gravity(&mut self, g_mg: [i32; 3]) {
        self.g_mg = g_mg;
        let g = self.setup.gravity(g_mg);
        self.world
            .set_gravity(Vec2::new(g[0], g[1]))
            .and_then(|()| self.world.body(self.ball)?.set_awake(true))
            .expect("Box2D gravity");
    }

    fn advance(&mut self) {
        let g = self.setup.gravity(self.g_mg);
        let decel = self.setup.decel;
        let m = self.mass;
        if decel > 0.0 {
            self.world
                .body(self.ball)
                .and_then(|mut b| {
                    let v = b.linear_velocity()?;
                    match resistance(decel, FRAME_S, [v.x, v.y], g) {
                        Resistance::Off => Ok(()),
                        Resistance::Push(a) => {
                            b.apply_force_to_center(Vec2::new(a[0] * m, a[1] * m), false)
                        }
                        Resistance::Hold(a) => {
                            b.set_linear_velocity(Vec2::new(0.0, 0.0))?;
                            b.apply_force_to_center(Vec2::new(a[0] * m, a[1] * m), false)
                        }
                    }
                })
                .expect("Box2D rolling resistance");
        }
        self.world
            .step(FRAME_S, self.substeps)
            .map(drop)
            .expect("Box2D step");
    }

    fn state(&mut self) -> ([f64; 2], [f64; 2]) {
        let b = self.world.body(self.ball).expect("Box2D marble");
        let (p, v) = (
            b.position().expect("Box2D position"),
            b.linear_velocity().expect("Box2D velocity"),
        );
        ([p.x as f64, p.y as f64], [v.x as f64, v.y as f64])
    }

    fn touching(&mut self) -> bool {
        self.world
            .body(self.ball)
            .and_then(|b| b.contact_data())
            .expect("Box2D contacts")
            .iter()
            .any(|c| c.manifold.point_count > 0)
    }
}
