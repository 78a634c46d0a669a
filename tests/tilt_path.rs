//! The whole tilt path as a user feels it: an accelerometer reading (mg, board
//! frame) → `Session` (plausibility, low-pass, calibration) → physics. A board held
//! at θ must roll the marble at 5/7·g·sin θ (effect `rolling`) or slide it at
//! g·sin θ (rolling off), and a near-level board must hold a resting marble by
//! rolling resistance (effect `friction`), not by a bias on every reading.
//!
//! "Reading" is what the accelerometer reports: the board frame's reaction to
//! gravity. A flat board reads `(0, +1000, 0)`; tilted by θ towards +x' it reads
//! `(−1000 sin θ, 1000 cos θ, 0)`, and the marble rolls towards +x'.

use fixed::types::I8F24;
use marble_rolling::game::level::{parse, Level, LevelView};
use marble_rolling::game::rules::{GameConfig, Phase};
use marble_rolling::game::session::{Session, SYNTHETIC_TILT};
use marble_rolling::input::axes::AccelMg;
use marble_rolling::input::tilt::{GravityMg, TiltConfig};
use marble_rolling::physics::Scalar;

/// Standard gravity per milli-g, mm/s²: the physics' own constant
/// (`G_UM_PER_MG_X100` = 980 665 in src/physics/dynamics/integrate.rs).
const MM_S2_PER_MG: f64 = 9.806_65;
/// Occupancy words for the largest grid (127 × 127 tiles), as tests/levels.rs.
const W: usize = 1016;
/// The tilts measured, degrees.
const ANGLES: [f64; 5] = [1.0, 5.0, 10.0, 30.0, 60.0];
/// The pitch of the open floor (default `short_mm` + `long_mm`), mm.
const PITCH_MM: f64 = 12.0;
/// The measurement stops before the marble reaches this speed (the fixed-step
/// speed cap is 64 pitch/s = 768 mm/s per axis at this pitch and radius)…
const V_STOP_MM_S: f64 = 600.0;
/// …or this x' (the far wall's face is at 756 mm; the marble starts at 7 mm).
const X_STOP_MM: f64 = 700.0;
/// Frames the reading is held before measuring: the low-pass (τ ≈ 7.5 frames) is
/// then settled to 8·10⁻⁸ of a step.
const SETTLE_FRAMES: u32 = 128;

/// An open floor of the largest size, 63 × 2 cells: the marble starts in the top
/// row's first cell and runs along +x'; the goal is out of its way, in the row below.
fn open_floor(effects: &str, rolling_resistance: &str) -> String {
    let n = 127;
    let wall = "#".repeat(n);
    let row = |first: char| format!("#{first}{}#", ".".repeat(n - 3));
    format!(
        "name: open-floor\neffects: {effects}\nrolling_resistance: {rolling_resistance}\n\
         time_limit_s: 3600\n---\n{wall}\n{}\n{}\n{}\n{wall}\n",
        row('S'),
        row('.'),
        row('G'),
    )
}

/// The level's view with `rolling` as asked (the `effects` header can only add
/// effects to the default `rolling`, so sliding is set here).
fn view<'a>(level: &'a Level<'a, W>, rolling: bool) -> LevelView<'a> {
    let mut v = level.view();
    v.info.spec.effects.rolling = rolling;
    v
}

/// `(−1000 sin θ, 1000 cos θ, 0)`, exact (before the sensor rounds it to mg).
fn tilted(deg: f64) -> [f64; 3] {
    let t = deg.to_radians();
    [-1000.0 * t.sin(), 1000.0 * t.cos(), 0.0]
}

/// A deterministic stand-in for an accelerometer held still. It reports whole mg
/// (what `Session::frame` takes) with white noise of up to ±`noise_mg` on every
/// axis: each axis draws its noise from shuffled blocks of eight levels spread
/// evenly over ±`noise_mg` (so the noise sums to exactly zero over every block),
/// and each reading's rounding is carried over to the next (error feedback). So
/// over a window the readings average the true tilt, its sub-mg part included — as
/// a real sensor's own noise dithers its last digit — within (0.5 mg + a partial
/// block) / window.
struct Sensor {
    noise_mg: f64,
    rng: u64,
    block: [[f64; 8]; 3],
    used: usize,
    carry: [f64; 3],
}

impl Sensor {
    fn new(noise_mg: f64, seed: u64) -> Self {
        Sensor {
            noise_mg,
            rng: seed.wrapping_mul(0x9e37_79b9_7f4a_7c15) | 1,
            block: [[0.0; 8]; 3],
            used: 8,
            carry: [0.0; 3],
        }
    }

    /// xorshift64*.
    fn next(&mut self) -> u64 {
        self.rng ^= self.rng >> 12;
        self.rng ^= self.rng << 25;
        self.rng ^= self.rng >> 27;
        self.rng.wrapping_mul(0x2545_f491_4f6c_dd1d)
    }

    fn read(&mut self, truth: [f64; 3]) -> AccelMg {
        if self.used == 8 {
            for a in 0..3 {
                let mut b: [f64; 8] =
                    core::array::from_fn(|i| self.noise_mg * (2 * i as i32 - 7) as f64 / 7.0);
                for i in (1..8).rev() {
                    let j = (self.next() % (i as u64 + 1)) as usize;
                    b.swap(i, j);
                }
                self.block[a] = b;
            }
            self.used = 0;
        }
        let mut out = [0; 3];
        for a in 0..3 {
            let want = truth[a] + self.block[a][self.used] + self.carry[a];
            out[a] = want.round() as i32;
            self.carry[a] = want - out[a] as f64;
        }
        self.used += 1;
        AccelMg::from_array(out)
    }
}

/// One measurement: holds the readings `read()` for [`SETTLE_FRAMES`], puts the
/// marble back at rest at its start (the game restarts; the tilt path keeps its
/// settled state), then plays on until just before the speed or the floor runs out.
/// Returns the mean acceleration along x' over that window (mm/s²) and its frames.
fn measure<S: Scalar>(
    level: LevelView<'_>,
    tilt: TiltConfig,
    mut read: impl FnMut() -> AccelMg,
) -> (f64, u32) {
    let mut s = Session::<S>::new(level, GameConfig::DEFAULT, tilt).expect("sets up");
    for _ in 0..SETTLE_FRAMES {
        s.frame(read());
    }
    s.game_mut().restart();
    let hz = GameConfig::DEFAULT.frame_hz() as f64;
    let x0 = s.game().world().marbles()[0].pos.x.to_f64() * PITCH_MM;
    assert_eq!(s.game().world().marbles()[0].vel.x.to_f64(), 0.0);
    let (mut frames, mut v) = (0u32, 0.0);
    loop {
        let mut next = s.clone();
        assert_eq!(next.frame(read()), Phase::Playing);
        let m = next.game().world().marbles()[0];
        let (x, nv) = (m.pos.x.to_f64() * PITCH_MM, m.vel.x.to_f64() * PITCH_MM);
        if nv >= V_STOP_MM_S || x >= X_STOP_MM {
            break;
        }
        assert!(x > x0);
        (s, v, frames) = (next, nv, frames + 1);
    }
    assert!(frames >= 8, "a window of {frames} frames");
    (v / (frames as f64 / hz), frames)
}

/// 5/7 rolling, 1 sliding.
fn share(rolling: bool) -> f64 {
    if rolling {
        5.0 / 7.0
    } else {
        1.0
    }
}

#[test]
fn a_steady_reading_reaches_the_physics_whole() {
    // Noise-free readings, rounded to whole mg as a sensor reports them: the
    // acceleration is exactly what the reading says (the path takes nothing off),
    // and so within 0.5 % of 5/7·g·sin θ wherever whole mg can say sin θ that
    // closely — at 1° the reading itself is 17 mg for 17.45 (the next test dithers).
    let src = open_floor("rolling", "0.01");
    let level = parse::<W>(&src).expect("parses");
    for rolling in [true, false] {
        for deg in ANGLES {
            let reading = AccelMg::from_array(tilted(deg).map(|v| v.round() as i32));
            for backend in ["i8f24", "f64"] {
                let l = view(&level, rolling);
                let (a, n) = match backend {
                    "i8f24" => measure::<I8F24>(l, SYNTHETIC_TILT, || reading),
                    _ => measure::<f64>(l, SYNTHETIC_TILT, || reading),
                };
                let of_reading = share(rolling) * MM_S2_PER_MG * -reading.x as f64;
                let ideal = share(rolling) * MM_S2_PER_MG * 1000.0 * deg.to_radians().sin();
                let (e_reading, e_ideal) = (a / of_reading - 1.0, a / ideal - 1.0);
                println!(
                    "{backend:5} rolling {rolling:5} {deg:2}°: reading {:4} mg, {a:8.2} mm/s² over \
                     {n:3} frames; vs the reading {:+.5} %, vs the ideal {:+.3} %",
                    reading.x,
                    100.0 * e_reading,
                    100.0 * e_ideal
                );
                assert!(e_reading.abs() < 1e-4, "{deg}°: {a} vs {of_reading}");
                let quantum = (-reading.x as f64 / (1000.0 * deg.to_radians().sin()) - 1.0).abs();
                assert!(e_ideal.abs() < 0.005 + quantum, "{deg}°: {a} vs {ideal}");
                if deg >= 5.0 {
                    assert!(e_ideal.abs() < 0.005, "{deg}°: {a} vs {ideal}");
                }
            }
        }
    }
}

#[test]
fn a_held_tilt_rolls_at_five_sevenths_g_sin_theta() {
    // The firmware's tilt path (stuck check on) fed a sensor held still at θ, with
    // ±5 mg of noise that dithers its whole-mg output: over the window the marble
    // accelerates at 5/7·g·sin θ (rolling) or g·sin θ (sliding) within 0.5 %, 1° to
    // 60°, whatever the noise's draw. (A 20 mg dead zone would take 20 mg off every
    // tilt: 1 076 instead of 1 216 mm/s² at 10°, nothing at all at 1°.)
    let src = open_floor("rolling", "0.01");
    let level = parse::<W>(&src).expect("parses");
    for rolling in [true, false] {
        for deg in ANGLES {
            let ideal = share(rolling) * MM_S2_PER_MG * 1000.0 * deg.to_radians().sin();
            for seed in 0..4 {
                let mut sensor = Sensor::new(5.0, 0x5eed + 10 * deg as u64 + seed);
                let truth = tilted(deg);
                let l = view(&level, rolling);
                let (a, frames) = measure::<I8F24>(l, TiltConfig::DEFAULT, || sensor.read(truth));
                let e = a / ideal - 1.0;
                println!(
                    "rolling {rolling:5} {deg:2}° seed {seed}: {a:8.2} mm/s² over {frames:3} \
                     frames, {} = {ideal:8.2}: {:+.3} %",
                    if rolling {
                        "5/7·g·sin θ"
                    } else {
                        "g·sin θ"
                    },
                    100.0 * e
                );
                assert!(e.abs() < 0.005, "{deg}°, rolling {rolling}: {a} vs {ideal}");
            }
        }
    }
}

/// Plays `frames` frames of `read()` on a level board and returns how far the marble
/// moved (mm) and whether it ever moved at all.
fn drift(level: LevelView<'_>, frames: u32, mut read: impl FnMut() -> AccelMg) -> (f64, bool) {
    let mut s =
        Session::<I8F24>::new(level, GameConfig::DEFAULT, TiltConfig::DEFAULT).expect("sets up");
    let start = s.game().world().marbles()[0].pos;
    let mut moved = false;
    for _ in 0..frames {
        assert_eq!(s.frame(read()), Phase::Playing);
        moved |= s.game().world().marbles()[0].pos != start;
    }
    let end = s.game().world().marbles()[0].pos;
    let d = (end - start).to_f64().map(|v| v * PITCH_MM);
    ((d[0] * d[0] + d[2] * d[2]).sqrt(), moved)
}

#[test]
fn rolling_resistance_holds_a_marble_on_a_near_level_board() {
    // Rolling resistance's static threshold: a resting marble stays put while the
    // in-plane pull is at most c_rr times the normal one (effects.rs, `Drag`), i.e.
    // tan θ ≤ c_rr — 10 mg, 0.57°, at the default c_rr = 0.01; 2° needs c_rr ≥ tan 2°
    // = 0.035. The board is held level (or tilted) with ±5 mg of sensor noise on
    // every axis, for 10 s.
    let frames = 10 * GameConfig::DEFAULT.frame_hz();
    let level_board = [0.0, 1000.0, 0.0];
    let case = |effects: &str, c_rr: &str, truth: [f64; 3], seed: u64| {
        let src = open_floor(effects, c_rr);
        let level = parse::<W>(&src).expect("parses");
        let mut sensor = Sensor::new(5.0, seed);
        drift(level.view(), frames, || sensor.read(truth))
    };
    // With friction (default c_rr = 0.01): level ±5 mg does not move the marble at
    // all; neither does a steady 0.5° (8.7 mg, under the 10 mg threshold).
    for seed in 1..=4 {
        let (d, moved) = case("rolling, friction", "0.01", level_board, seed);
        assert!(!moved, "level ±5 mg, seed {seed}: moved {d} mm");
    }
    let steady = AccelMg::from_array(tilted(0.5).map(|v| v.round() as i32));
    let src = open_floor("rolling, friction", "0.01");
    let level = parse::<W>(&src).expect("parses");
    let (d, moved) = drift(level.view(), frames, || steady);
    assert!(!moved, "0.5°: moved {d} mm");
    // 2° is over that threshold: the marble rolls. With c_rr = 0.05 (threshold
    // tan⁻¹ 0.05 = 2.9°) a 2° tilt with ±5 mg of noise holds it.
    let (d, _) = case("rolling, friction", "0.01", tilted(2.0), 5);
    println!("2° ±5 mg, c_rr 0.01: moved {d:.1} mm in 10 s");
    assert!(d > 100.0, "2° at c_rr 0.01 rolls: {d} mm");
    for seed in 6..=8 {
        let (d, moved) = case("rolling, friction", "0.05", tilted(2.0), seed);
        assert!(!moved, "2° ±5 mg at c_rr 0.05, seed {seed}: moved {d} mm");
    }
    // Without friction the same near-level boards do roll the marble: that is the
    // physics of a frictionless marble, and the path does not hide it.
    let (d, moved) = case("rolling", "0.01", level_board, 1);
    println!("level ±5 mg, no friction: moved {d:.2} mm in 10 s");
    assert!(moved && d > 0.1, "level ±5 mg, no friction: {d} mm");
    let src = open_floor("rolling", "0.01");
    let level = parse::<W>(&src).expect("parses");
    let (d, _) = drift(level.view(), frames, || steady);
    println!("0.5° steady, no friction: moved {d:.1} mm in 10 s");
    assert!(d > 100.0, "0.5°, no friction: {d} mm");
}

/// One plausibility check from the sensor to the world, and no clamp: a sample
/// just past the bounds is refused once, by the sensor's supervision (a fault it
/// counts), and the board's session (`TiltConfig::SENSOR`) judges nothing again;
/// a sample at the bounds reaches the world's gravity exactly, nothing clamped
/// on the way.
#[test]
fn a_reading_is_judged_once_and_reaches_the_world_unclamped() {
    use marble_rolling::input::event::Fault;
    use marble_rolling::input::sensor::{
        AccelMg, Action, AxisMap, Read, SupervisorConfig, TiltPipeline,
    };
    use marble_rolling::input::tilt::{Plausibility, TiltError, TiltFilter};

    let src = open_floor("rolling", "0.01");
    let level = parse::<W>(&src).expect("parses");
    let mut pipeline = TiltPipeline::new(AxisMap::IDENTITY, SupervisorConfig::DEFAULT);
    // The stuck check off: this sensor's samples are noise-free, so they repeat.
    let sensor = TiltConfig {
        stuck_samples: 0,
        ..TiltConfig::SENSOR
    };
    let mut session =
        Session::<I8F24>::new(level.view(), GameConfig::DEFAULT, sensor).expect("sets up");
    let bound = Plausibility::DEFAULT.max_total_mg as i32;
    assert!(
        session.game().world().params().mg_max >= bound,
        "the level takes a believed reading's pull whole"
    );

    // Just past the total magnitude a hand-held toy feels: the supervision
    // refuses it as implausible, once, and keeps the last good sample (level).
    let step = pipeline.feed(Read::Sample(AccelMg::new(-(bound + 1), 0, 0)));
    assert_eq!(step.action, Action::KeepLast(AccelMg::LEVEL));
    assert_eq!(pipeline.supervisor().last_fault(), Some(Fault::Implausible));
    assert_eq!(pipeline.supervisor().total_faults(), 1);
    session.frame(pipeline.tilt());
    assert_eq!(
        session.tilt_errors(),
        (0, None),
        "the session judges no more"
    );
    assert_eq!(session.game().world().gravity_mg(), [0, -1000, 0]);

    // At the bound: believed, and once the low-pass has settled (it reaches
    // the reading exactly) the world's pull is the reading, negated, to the
    // milli-g.
    let step = pipeline.feed(Read::Sample(AccelMg::new(-bound, 0, 0)));
    assert_eq!(step.action, Action::Use(AccelMg::new(-bound, 0, 0)));
    assert_eq!(pipeline.supervisor().total_faults(), 1);
    for _ in 0..SETTLE_FRAMES {
        session.frame(pipeline.tilt());
    }
    assert_eq!(session.tilt_errors(), (0, None));
    assert_eq!(session.game().world().gravity_mg(), [bound, 0, 0]);

    // The check the session leaves out is the same rule, made where a reading
    // comes from anything but a sensor: a filter that judges on entry refuses
    // that sample too, a filter fed the sensor's samples does not ask.
    let past = AccelMg::new(-(bound + 1), 0, 0);
    assert!(matches!(
        TiltFilter::new(TiltConfig::DEFAULT).push(past),
        Err(TiltError::Magnitude { .. })
    ));
    assert_eq!(
        TiltFilter::new(TiltConfig::SENSOR).push(past),
        Ok(GravityMg::new(bound + 1, 0, 0))
    );
    assert_eq!(TiltConfig::SENSOR.plausibility, None);
    assert_eq!(
        TiltConfig {
            plausibility: None,
            ..TiltConfig::DEFAULT
        },
        TiltConfig::SENSOR,
        "the sensor's tilt path differs from the default only in the check it leaves out"
    );
}
