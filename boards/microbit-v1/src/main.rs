//! Marble Rolling firmware for the BBC micro:bit v1 (nRF51822, Cortex-M0,
//! 16 KiB RAM, 256 KiB flash) — and, the very same ELF, in QEMU's
//! `microbit` machine.
//!
//! * On a board (`cargo microbit-v1`: `probe-rs run --chip nRF51822_xxAA`):
//!   tilt to play; the accelerometer is found by its `WHO_AM_I`
//!   ([`sensor`]); the log goes over RTT.
//! * In QEMU (`cargo microbit-v1 -- --demo`): the semihosting command line
//!   picks the mode (`marble_rolling::board::microbit_v1::Options`). With
//!   `--demo` the autopilot plays every built-in level and three generated
//!   mazes and the firmware logs
//!   per level `demo <n>/<total> level=<name> outcome=<..> steps=<..>
//!   state_hash=<16 hex>` (as the mps2 board, so `cargo sim` can be compared
//!   with it), every frame that stays on the LEDs for 80 ms or more with its
//!   time span (`display frame …`, for the GPIO check), then the CPU load,
//!   the RAM use (statics + stack high-water mark) and a summary, and exits
//!   0 only if every level was won (101 on a panic). `--demo --profile`
//!   counts each frame's instructions (`profile NAME: …`), then profiles the
//!   difficulty-9 mazes and the stress scenes as the mps2 board does
//!   (`app::profile_scenes`): in a build with the `profile` feature (the
//!   xtask builds one for it), whose code the image for a board leaves out;
//!   an image without it says so and plays the plain demo. Without `--demo` it
//!   plays: QEMU's TWI is a stub with no accelerometer behind it, so the
//!   sensor supervision reports the sensor down and the game waits, showing
//!   the fault cross, as on a board with a broken sensor (`--seconds=N`
//!   ends such a run).
//!
//! # Time: TIMER0, on the board as in QEMU
//!
//! embassy-nrf's time driver counts the RTC, which QEMU's `microbit` machine
//! does not emulate (it reads 0): this crate brings its own driver on TIMER0
//! (1 MHz, 32 bits extended to 64, compare interrupts), and uses it on the
//! board too rather than the RTC there — one code path, the one CI runs in
//! QEMU. The cost is the 16 MHz clock staying requested while the core
//! sleeps, small next to the LEDs' milliamperes, and the LED scan (4.5 kHz
//! BCM slices on TIMER1) keeps it running most of the time anyway. The full
//! argument is in [`hw`].
//!
//! # Memory map
//!
//! The micro:bit v1's nRF51822 has 256 KiB of flash in **1 KiB pages** and
//! 16 KiB of RAM (`memory.x`). embassy-nrf 0.11 declares its `nrf51` target
//! with 4 KiB pages and 128 KiB of flash: whoever adds flash storage (not
//! built here) must use 1 KiB pages and may use all 256 KiB.
//!
//! The tasks are the shared ones of `marble_rolling::app` (input, game via
//! `app::game_task::<5, 5, PILOT, EVENTS>`, display); this crate is the wiring:
//! [`hw`] (time driver on TIMER0, executor, CPU meter, stack, emulation
//! detection), [`display`] (the 3 × 9 matrix on TIMER1), [`sensor`] (TWI and
//! accelerometers), [`log`] (defmt over semihosting or RTT).
#![no_std]
#![no_main]

mod display;
mod hw;
mod log;
mod sensor;

use core::sync::atomic::{AtomicU32, Ordering};

use marble_board_runtime::heartbeat::poll_beating;
use marble_rolling::app::{self, GameMode, Links, TiltInput};
use marble_rolling::board::levels_region;
use marble_rolling::board::microbit_v1::{
    LoadReport, Options, HEIGHT, MAZE_REACH, RAM_BUDGET_BYTES, RAM_BYTES, WATCHDOG_TIMEOUT_TICKS,
    WIDTH,
};
use marble_rolling::board::watchdog::{Heartbeats, Task, Verdict, WatchdogGate, WATCHDOG_CHECK_MS};
use marble_rolling::game::endless::{MazeSlot, Seeds};
#[cfg(feature = "profile")]
use marble_rolling::game::rules::Phase;
use marble_rolling::input::tilt::TiltConfig;

/// The links between the tasks.
static LINKS: Links<WIDTH, HEIGHT> = Links::new();

/// Each task's heartbeat, for the watchdog (`board::watchdog`: input beats per
/// poll, the game each time it is polled, the display per refresh).
pub static HEARTBEATS: Heartbeats = Heartbeats::new();

/// The autopilot is linked: the demo needs it.
const PILOT: bool = true;

/// The stepper every board plays (`GameConfig::DEFAULT`, events): with the v1's
/// flash budget at 144 KiB of its 256 KiB it fits (`cargo xtask
/// check-microbit-v1` and docs/microbit-revisions.md have the figures).
const EVENTS: bool = marble_rolling::game::rules::DEFAULT_EVENTS;

/// Room for the endless run's generated maze ([`MAZE_REACH`]).
type Mazes = MazeSlot<{ MAZE_REACH.words() }, { MAZE_REACH.text_bytes() }>;

#[cortex_m_rt::entry]
fn main() -> ! {
    hw::stack::paint();
    hw::start_time();
    let emulated = hw::detect_emulation();
    let options = hw::options();
    defmt::info!(
        "Marble Rolling on micro:bit v1 ({=str}): {}, {=u32} frames/s",
        if emulated { "QEMU" } else { "nRF51822" },
        options,
        app::FRAME_HZ
    );
    let calibration = hw::cpu_meter::calibrate();
    if emulated {
        defmt::info!(
            "cpu meter calibration: {=u32} instructions in {=u32} us = {=u64} milli-us per instruction (icount shift=7 gives 128: {=bool})",
            calibration.instructions,
            calibration.us,
            calibration.milli_us_per_instruction(),
            calibration.matches_icount()
        );
    }
    display::start();
    hw::executor::run(spawn)
}

/// Spawns the tasks for the [`Options`] of this run.
#[inline(never)]
fn spawn(spawner: embassy_executor::Spawner) {
    let options = hw::options();
    match display_task(options.headless() && options.frame_log) {
        Ok(token) => spawner.spawn(token),
        Err(_) => hw::fatal("cannot spawn the display"),
    }
    match game(options) {
        Ok(token) => spawner.spawn(token),
        Err(_) => hw::fatal("cannot spawn the game"),
    }
    // In the demo too: the sensor path runs (probe, configuration, polls,
    // supervision) while the autopilot plays, so that the stack high-water
    // covers it; there its events are counted, not given to the game.
    match input(options.demo) {
        Ok(token) => spawner.spawn(token),
        Err(_) => hw::fatal("cannot spawn the input"),
    }
    match watchdog() {
        Ok(token) => spawner.spawn(token),
        Err(_) => hw::fatal("cannot spawn the watchdog"),
    }
    if let Some(seconds) = options.seconds {
        match stop_after(seconds) {
            Ok(token) => spawner.spawn(token),
            Err(_) => hw::fatal("cannot spawn the stopper"),
        }
    }
}

#[embassy_executor::task]
async fn display_task(log_frames: bool) -> ! {
    let mut matrix = display::Matrix::new(&LINKS.status, log_frames);
    app::display_task(&LINKS, &mut matrix).await
}

/// Re-initialisations and faults of the sensor path so far (the demo's
/// summary prints them).
static SENSOR_REINITS: AtomicU32 = AtomicU32::new(0);
/// See [`SENSOR_REINITS`].
static SENSOR_FAULTS: AtomicU32 = AtomicU32::new(0);

/// The accelerometer and its supervision. In the demo the autopilot needs
/// no tilt and a sensor going down must not pause it (QEMU's TWI stub is no
/// sensor): the events are only counted.
#[embassy_executor::task]
async fn input(demo: bool) -> ! {
    let mut input = sensor::Input::new();
    if !demo {
        app::input_task(&LINKS, &mut input).await
    }
    loop {
        if let marble_rolling::input::event::InputEvent::Tilt(tilt) = input.next_event().await {
            // Shown in the summary only: the demo's game reads no tilt.
            LINKS.tilt.set(tilt);
        }
        SENSOR_REINITS.store(input.reinits(), Ordering::Relaxed);
        SENSOR_FAULTS.store(input.faults(), Ordering::Relaxed);
    }
}

/// The most watchdog checks in a row without a pet (the demo prints it).
static WATCHDOG_WORST: AtomicU32 = AtomicU32::new(0);

/// Pets the watchdog whenever every task has beaten since the last pet; a
/// stalled task stops the pets and the board resets (`hw::watchdog`).
#[embassy_executor::task]
async fn watchdog() -> ! {
    // The v1 links no sound and no records task: they wait for work that never
    // comes, and the gate excuses a waiting task (else it would never pet).
    HEARTBEATS.waiting(Task::Sound);
    HEARTBEATS.waiting(Task::Records);
    let mut gate = WatchdogGate::new(HEARTBEATS.snapshot());
    let mut ticker =
        embassy_time::Ticker::every(embassy_time::Duration::from_millis(WATCHDOG_CHECK_MS));
    hw::watchdog::start();
    loop {
        ticker.next().await;
        match gate.check(HEARTBEATS.snapshot()) {
            Verdict::Pet => hw::watchdog::pet(),
            Verdict::Wait { stalled, checks } => {
                if u32::from(checks) > WATCHDOG_WORST.load(Ordering::Relaxed) {
                    WATCHDOG_WORST.store(u32::from(checks), Ordering::Relaxed);
                }
                if checks == 5 {
                    defmt::warn!("watchdog: no pet for 5 checks, stalled: {}", stalled);
                }
            }
        }
    }
}

/// `--seconds=N`: ends a headless play after `N` seconds, with the game's
/// status.
#[embassy_executor::task]
async fn stop_after(seconds: u32) {
    embassy_time::Timer::after_secs(u64::from(seconds)).await;
    let status = LINKS.status.get();
    defmt::info!(
        "stop after {=u32} s: level {=u8}, {} after {=u32} frames, sensor down: {=bool}",
        seconds,
        status.level,
        status.phase,
        status.frames,
        status.sensor_down
    );
    report_memory();
    hw::exit(0)
}

/// Logs RAM use: statics + stack high-water mark against the budget.
fn report_memory() {
    let stack = hw::stack::high_water();
    defmt::info!(
        "ram: statics {=usize} B + stack high-water {=usize} B = {=usize} B of {=u32} B (budget {=u32} B)",
        stack.statics,
        stack.used,
        stack.statics + stack.used,
        RAM_BYTES,
        RAM_BUDGET_BYTES
    );
}

#[embassy_executor::task]
async fn game(options: Options) {
    let mode = if options.demo {
        GameMode::Demo { records: false }
    } else {
        // No random source is used here: the mazes' seeds are the level
        // count, as in the demo.
        GameMode::Play {
            tilt: TiltConfig::SENSOR,
            seeds: Seeds::Count,
        }
    };
    if options.demo {
        // The baseline: display scanning and timers, no game.
        let before = hw::cpu_meter::sample();
        // A second, beating for the watchdog (the game is not running yet).
        for _ in 0..10 {
            HEARTBEATS.beat(Task::Game);
            embassy_time::Timer::after_millis(100).await;
        }
        let after = hw::cpu_meter::sample();
        if let Some(load) = LoadReport::between(&hw::cpu_meter::calibration(), before, after) {
            defmt::info!(
                "baseline load (display scanning, timers, no game): {=u64} instructions/s = {=u64}.{=u64:02} % of 16 MHz",
                load.instructions_per_second,
                load.centipercent_of_16mhz / 100,
                load.centipercent_of_16mhz % 100
            );
        }
        defmt::info!(
            "stack high-water before the game: {=usize} B",
            hw::stack::high_water().used
        );
    }
    let start = hw::cpu_meter::sample();
    let profile = options.demo && options.profile;
    if profile && !cfg!(feature = "profile") {
        defmt::warn!(
            "--profile: this image has no profile (build it with the `profile` feature, as `cargo microbit-v1 -- --demo --profile` does); playing the demo"
        );
    }
    #[cfg(feature = "profile")]
    if profile {
        // Interrupts off while a frame is counted: the display's slices
        // stretch, so this run's LEDs and CPU load are not the demo's.
        LINKS.meter.set(Some(hw::cpu_meter::meter));
    }
    // The player's levels (cargo xtask hex --level), played first, parsed
    // into the maze slot in turn; one log line says what the region holds or
    // why it is ignored.
    let region = levels_region::at_boot(hw::levels_region());
    let mut mazes = Mazes::new(MAZE_REACH).with_region(region);
    let exit = {
        let game = core::pin::pin!(app::game_task::<WIDTH, HEIGHT, PILOT, EVENTS, _, _>(
            &LINKS, mode, &mut mazes
        ));
        // Being polled at the frame rate is the game's proof of life (its loop
        // is `app::game_task`'s).
        poll_beating(|| HEARTBEATS.beat(Task::Game), game).await
    };
    let end = hw::cpu_meter::sample();
    #[cfg(feature = "profile")]
    if profile {
        // The top-difficulty mazes and the stress scenes, as the mps2 board
        // profiles them. Seconds without a poll of the other tasks: the
        // watchdog is petted here after each frame (`--profile` comes from
        // the semihosting command line, so this runs in QEMU only).
        // Counted with the meter the levels' profile uses (`app::Meter`).
        app::profile_scenes::<WIDTH, HEIGHT, PILOT, EVENTS, _, _>(
            &mut mazes,
            |session, reading| {
                let mut phase = Phase::Playing;
                let counted =
                    hw::cpu_meter::meter(&mut || phase = session.frame_in::<EVENTS>(reading));
                hw::watchdog::pet();
                (phase, counted)
            },
        );
    }
    let summary = match exit.demo_summary() {
        Ok(summary) => summary,
        Err(e) => {
            defmt::error!("cannot set up a level: {}", e);
            hw::exit(1)
        }
    };
    report_memory();
    match LoadReport::between(&hw::cpu_meter::calibration(), start, end) {
        Some(load) => defmt::info!(
            "cpu load: {=u64} busy instructions in {=u64} us of firmware time = {=u64} instructions/s = {=u64}.{=u64:02} % of a 16 MHz Cortex-M0 ({=u32} frames/s, {=u32} refreshes/s)",
            load.busy_instructions,
            load.firmware_us,
            load.instructions_per_second,
            load.centipercent_of_16mhz / 100,
            load.centipercent_of_16mhz % 100,
            app::FRAME_HZ,
            app::REFRESH_HZ,
        ),
        None => defmt::warn!("cpu load: no time elapsed"),
    }
    defmt::info!(
        "demo sensor: {=u32} re-inits, {=u32} faults, last tilt {=i32} {=i32} {=i32} mg",
        SENSOR_REINITS.load(Ordering::Relaxed),
        SENSOR_FAULTS.load(Ordering::Relaxed),
        LINKS.tilt.get().x,
        LINKS.tilt.get().y,
        LINKS.tilt.get().z
    );
    defmt::info!(
        "watchdog: longest wait without a pet {=u32} ms (it resets at {=u32} ms)",
        WATCHDOG_WORST.load(Ordering::Relaxed) * WATCHDOG_CHECK_MS as u32,
        WATCHDOG_TIMEOUT_TICKS * 1000 / 32_768
    );
    defmt::info!(
        "demo summary: {=u8}/{=u8} levels won, {=u64} physics steps in {=u64} frames: {=str}",
        summary.won,
        summary.levels,
        summary.steps,
        summary.frames,
        summary.verdict().as_str()
    );
    hw::exit(summary.verdict().exit_code())
}
