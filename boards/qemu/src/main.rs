//! Marble Rolling firmware for QEMU's `mps2-an386` (Cortex-M4F).
//!
//! `cargo qemu` plays on the terminal (UART0); `cargo qemu -- --demo` (or any
//! run without a terminal on stdin) runs the deterministic headless demo: the
//! autopilot plays every built-in level and the endless run's first three
//! generated mazes, one log line per level (outcome, physics steps,
//! `state_hash`, as `cargo sim -- --level <name> --autopilot --json` or
//! `cargo sim -- --generate SEED --size N --storeys S --difficulty D
//! --autopilot --json` reports them; `cargo xtask check-demo` compares the
//! two), then the
//! CPU load, the stack high-water mark, the instruction count of a game frame,
//! and a summary. QEMU exits 0 when every level was won, 1 otherwise, 101 on
//! a panic. The runner is `cargo qemu` (xtask); it tells the firmware its mode
//! on the semihosting command line (see `marble_rolling::board::qemu::Options`).
//!
//! The tilt comes from a virtual LSM303AGR on a virtual TWIM, read through the
//! micro:bit's driver and sensor supervision ([`sensor`]): the terminal's keys
//! set the chip's tilt and inject faults (`1` NAK, `2` stuck bus, `3` frozen
//! data, `4` garbage, `5` chip reset, `0` healthy). `--fault-script` runs the
//! headless [`fault_script`] instead of the demo (exit 0 only if every
//! expectation held); `--no-copy-buffer` builds the virtual TWIM without a
//! copy buffer, which the micro:bit's TWIM needs for the driver's reads.
//!
//! The tasks below are thin wrappers: the logic is in `marble_rolling::app`.
#![no_std]
#![no_main]

mod fault_script;
mod sensor;

use defmt_semihosting as _;
use marble_rolling::app::GhostKit;
use marble_rolling::app::{self, GameExit, GameMode, Links, SensorTotals, TerminalSound};
use marble_rolling::board::qemu::cpu_meter::LoadReport;
use marble_rolling::board::qemu::ram_flash::{self, RamFlash};
use marble_rolling::board::qemu::terminal::{restore_terminal, Terminal};
use marble_rolling::board::qemu::virtual_i2c::VirtualTwim;
use marble_rolling::board::qemu::virtual_matrix::VirtualMatrix;
use marble_rolling::board::qemu::{
    Options, GHOSTS_BYTES, GHOST_BYTES, HEIGHT, MAZE_REACH, PLAY_TILT, QEMU_RAM, WIDTH,
};
use marble_rolling::board::virtual_lsm303agr::{ChipControl, VirtualLsm303agr, MICROBIT_V2};
use marble_rolling::game::endless::{Endless, MazeSlot, Seeds, Stage, DEMO_MAZES};
use marble_rolling::game::levels::LEVELS;
use marble_rolling::game::rules::Phase;
use marble_rolling::game::session::SYNTHETIC_TILT;
use marble_rolling::input::axes::AccelMg;
use marble_rolling::matrix::{Frame, OnTimeIntegrator, Scanner};
use marble_rolling::player::Player;
use marble_rolling::records::{Ghosts, Records};

use marble_qemu as hw;

use hw::uart::{UartConsole, UartRx};
use sensor::{Bus, Keys, QemuInput, SensorReport, TimedTwim};

/// The links between the tasks.
static LINKS: Links<WIDTH, HEIGHT> = Links::new();

/// The virtual accelerometer's tilt and injected fault, shared by the keys,
/// the fault script and its bus.
static CHIP: ChipControl = ChipControl::new();

/// What the sensor input did (for the fault script).
static REPORT: SensorReport = SensorReport::new();

/// The largest virtual TWIM copy buffer `--twim-copy-buffer=N` can ask for.
const MAX_COPY_BUFFER: usize = 64;

/// This board has the autopilot (the demo, the `p` key).
const PILOT: bool = true;

/// The stepper every board plays (`GameConfig::DEFAULT`); `cargo sim` plays the
/// same game.
const EVENTS: bool = marble_rolling::game::rules::DEFAULT_EVENTS;

/// Room for the endless run's generated maze ([`MAZE_REACH`]).
type Mazes = MazeSlot<{ MAZE_REACH.words() }, { MAZE_REACH.text_bytes() }>;

/// Headless runs log the perceived matrix (when it changed) every this many
/// refreshes (5 s).
const LOG_MATRIX_EVERY: u32 = app::REFRESH_HZ * 5;

#[cortex_m_rt::entry]
fn main() -> ! {
    // Before anything else uses the stack.
    hw::stack::paint();
    let Some(mut core) = cortex_m::Peripherals::take() else {
        hw::fatal("core peripherals already taken");
    };
    // First, so that log timestamps start at 0.
    hw::start_time(&mut core.SYST);
    let options = hw::options();
    defmt::info!(
        "Marble Rolling on QEMU mps2-an386: {}, {=usize}x{=usize} virtual matrix, {=u32} frames/s",
        options,
        WIDTH,
        HEIGHT,
        app::FRAME_HZ
    );

    let calibration = hw::cpu_meter::calibrate();
    defmt::info!(
        "cpu meter calibration: {=u32} instructions in {=u32} ticks = {=u64} milliticks/instruction (icount shift=7 gives 3200: {=bool}), timer read overhead {=u32} ticks",
        calibration.instructions,
        calibration.ticks,
        calibration.milliticks_per_instruction(),
        calibration.matches_icount(),
        calibration.overhead_ticks
    );
    if options.interactive {
        hw::uart::init();
    }

    hw::executor::run(|spawner| {
        let display = display(options.interactive);
        let input = sensor_input(options);
        match (display, input) {
            (Ok(display), Ok(input)) => {
                spawner.spawn(display);
                spawner.spawn(input);
            }
            _ => hw::fatal("cannot spawn tasks"),
        }
        if options.interactive {
            match sound() {
                Ok(token) => spawner.spawn(token),
                Err(_) => hw::fatal("cannot spawn the sound task"),
            }
        }
        // The player's best times; in the demo only for the records check
        // (`--records`: the autopilot's wins are never a player's records).
        if options.records {
            match records() {
                Ok(token) => spawner.spawn(token),
                Err(_) => hw::fatal("cannot spawn the records task"),
            }
        }
        if options.fault_script {
            match fault_script_task(options) {
                Ok(token) => spawner.spawn(token),
                Err(_) => hw::fatal("cannot spawn the fault script"),
            }
        } else {
            match game(options) {
                Ok(token) => spawner.spawn(token),
                Err(_) => hw::fatal("cannot spawn the game"),
            }
        }
    })
}

/// The tilt from the virtual LSM303AGR through the micro:bit's driver and
/// supervision, with the terminal's keys when interactive.
///
/// In the demo the game ignores the tilt (the autopilot reads the game
/// itself, and `app::demo` feeds the session the autopilot's reading) and a
/// healthy virtual chip never reports the sensor down, so the demo plays
/// exactly as the host simulator does: same steps, same state hashes. The
/// polling only costs CPU time.
#[embassy_executor::task]
async fn sensor_input(options: Options) -> ! {
    // embassy-nrf's `tx_ram_buffer`: in this task's state, so in RAM.
    let mut copy = [0u8; MAX_COPY_BUFFER];
    let len = options.twim_copy_buffer.min(MAX_COPY_BUFFER);
    let copy = match copy.get_mut(..len) {
        Some(copy) => copy,
        None => &mut [],
    };
    let twim = VirtualTwim::new(
        VirtualLsm303agr::placed(MICROBIT_V2),
        &CHIP,
        copy,
        sensor::now_us as fn() -> u64,
        QEMU_RAM,
    );
    let sensor = lsm303agr::Lsm303agr::new_with_i2c(Bus::new(TimedTwim::new(twim)));
    let keys = options.interactive.then(|| Keys::new(UartRx, UartConsole));
    let mut input = QemuInput::new(sensor, keys, &CHIP, &REPORT);
    app::input_task(&LINKS, &mut input).await
}

/// `--fault-script`: the script instead of the game; exits with its verdict.
#[embassy_executor::task]
async fn fault_script_task(options: Options) {
    let copy_buffer = options.twim_copy_buffer.min(MAX_COPY_BUFFER);
    let verdict = fault_script::run(&LINKS, &CHIP, &REPORT, copy_buffer).await;
    hw::exit(if verdict.passed() { 0 } else { 1 })
}

#[embassy_executor::task]
async fn display(interactive: bool) -> ! {
    if interactive {
        app::display_task(
            &LINKS,
            &mut VirtualMatrix::new(Some(Terminal::new(UartConsole, || LINKS.status.get())), 0),
        )
        .await
    } else {
        let mut matrix = VirtualMatrix::<Terminal<UartConsole>>::new(None, LOG_MATRIX_EVERY);
        app::display_task(&LINKS, &mut matrix).await
    }
}

/// The records' region: four 4 KiB pages, as on the micro:bit v2.
const RECORDS_BYTES: usize = 4 * ram_flash::PAGE;

/// The ghosts, in a region and with buffers the micro:bit v2's size
/// (`board::qemu::{GHOSTS_BYTES, GHOST_BYTES}`).
type Kit = GhostKit<RamFlash<GHOSTS_BYTES>, GHOST_BYTES>;

/// The ghosts over their image loaded from its host file, saved after each
/// write.
fn open_ghosts() -> Option<Kit> {
    let mut flash = RamFlash::<GHOSTS_BYTES>::new();
    hw::ghosts_file::load(flash.image_mut());
    let store = Ghosts::new(flash, 0..GHOSTS_BYTES as u32)?;
    Some(GhostKit::new(store, |flash| {
        hw::ghosts_file::save(flash.image())
    }))
}

/// The best times, in a RAM flash image kept in a host file between runs
/// (`marble_rolling::board::qemu::ram_flash`): the same records code as the v2.
#[embassy_executor::task]
async fn records() -> ! {
    let Some(mut records) = open_records() else {
        hw::fatal("the records' region is not whole pages")
    };
    app::records_task(&LINKS, &mut records, |flash| {
        hw::records_file::save(flash.image())
    })
    .await
}

/// The records over the image loaded from the host file (outside the task's
/// future, which then holds one image, not two).
fn open_records() -> Option<Records<RamFlash<RECORDS_BYTES>>> {
    let mut flash = RamFlash::<RECORDS_BYTES>::new();
    hw::records_file::load(flash.image_mut());
    Records::new(flash, 0..RECORDS_BYTES as u32)
}

/// Asleep: a dark matrix until a key (a command, or a tilt key).
async fn sleep_until_touched() {
    defmt::info!("asleep: a dark matrix until a key");
    LINKS.frames.signal(Frame::new());
    let tilt = LINKS.tilt.get();
    loop {
        embassy_time::Timer::after_millis(10).await;
        if LINKS.events.try_receive().is_ok() || LINKS.tilt.get() != tilt {
            defmt::info!("awake");
            return;
        }
    }
}

/// The game's sounds: logged, and the terminal's bell on a win.
#[embassy_executor::task]
async fn sound() -> ! {
    app::sound_task(&LINKS, &mut TerminalSound::new(UartConsole)).await
}

#[embassy_executor::task]
async fn game(options: Options) {
    // No random source here: the mazes' seeds are the level count, as in the
    // demo.
    let mode = if options.interactive {
        GameMode::Play {
            tilt: PLAY_TILT,
            level: 0,
            seeds: Seeds::Count,
        }
    } else {
        GameMode::Demo {
            records: options.records,
        }
    };
    if !options.interactive {
        // The baseline: the display scanning a blank frame, the timers and
        // the executor, before the game starts.
        let before = hw::cpu_meter::sample();
        embassy_time::Timer::after_secs(1).await;
        let after = hw::cpu_meter::sample();
        if let Some(load) = LoadReport::between(&hw::cpu_meter::calibration(), before, after) {
            defmt::info!(
                "baseline load (display scanning, timers, no game): {=u64} instructions/s = {=u64}.{=u64:02} % of 64 MHz",
                load.instructions_per_second,
                load.centipercent_of_64mhz / 100,
                load.centipercent_of_64mhz % 100
            );
        }
    }
    let mut mazes = Mazes::new(MAZE_REACH);
    // Each level's best run (always when interactive; `--ghosts` in the
    // demo: the ghosts check).
    let mut ghosts = if options.ghosts { open_ghosts() } else { None };
    if options.ghosts && ghosts.is_none() {
        hw::fatal("the ghosts' region is not whole pages");
    }
    // The mps2-an386 board has no levels region (no .hex carries it there):
    // the slot has none, and the run starts with the built-in levels.
    let start = hw::cpu_meter::sample();
    let mut exit = app::game_task::<WIDTH, HEIGHT, PILOT, EVENTS, _, _>(
        &LINKS,
        mode,
        &mut mazes,
        ghosts.as_mut(),
    )
    .await;
    // Idle for two minutes: QEMU has no power to save; it blanks the matrix,
    // waits for a key, and resumes at the start of the level (as the v2 does
    // from System OFF).
    while let GameExit::Asleep { level } = exit {
        sleep_until_touched().await;
        let mode = GameMode::Play {
            tilt: PLAY_TILT,
            level,
            seeds: Seeds::Count,
        };
        exit = app::game_task::<WIDTH, HEIGHT, PILOT, EVENTS, _, _>(
            &LINKS,
            mode,
            &mut mazes,
            ghosts.as_mut(),
        )
        .await;
    }
    let end = hw::cpu_meter::sample();
    if exit == GameExit::Quit {
        restore_terminal(&mut UartConsole);
        defmt::info!("quit");
    }
    let summary = match exit.demo_summary() {
        Ok(summary) => summary,
        Err(e) => {
            defmt::error!("cannot set up a level: {}", e);
            hw::exit(1)
        }
    };
    let stack = hw::stack::high_water();
    defmt::info!(
        "stack high-water mark: {=usize} of {=usize} bytes",
        stack.used,
        stack.size
    );
    if options.interactive {
        // No -icount: the CPU meter's figures would mean nothing.
        hw::exit(0)
    }
    match LoadReport::between(&hw::cpu_meter::calibration(), start, end) {
        Some(load) => {
            defmt::info!(
                "cpu load: {=u64} busy instructions in {=u64} us of firmware time = {=u64} instructions/s = {=u64}.{=u64:02} % of a 64 MHz Cortex-M4 ({=u32} frames/s, {=u32} refreshes/s)",
                load.busy_instructions,
                load.firmware_us,
                load.instructions_per_second,
                load.centipercent_of_64mhz / 100,
                load.centipercent_of_64mhz % 100,
                app::FRAME_HZ,
                app::REFRESH_HZ,
            );
        }
        None => defmt::warn!("cpu load: no time elapsed"),
    }
    profile(&mut mazes);
    // The first configuration is not a re-init; a fault-free demo has no other
    // and no fault (a long frame that starves the input task would show here).
    let sensor = SensorTotals::from_configurations(REPORT.reinits(), REPORT.faults());
    let verdict = summary.verdict_with_sensor(sensor);
    defmt::info!(
        "demo summary: {=u8}/{=u8} levels won, {=u64} physics steps in {=u64} frames, sensor re-inits {=u32}, sensor faults {=u32}: {=str}",
        summary.won,
        summary.levels,
        summary.steps,
        summary.frames,
        sensor.reinits,
        sensor.faults,
        verdict.as_str()
    );
    hw::exit(verdict.exit_code())
}

/// Counts the instructions of the game's per-frame work (autopilot reading,
/// `Session::frame` = 8 physics steps, rendering) frame by frame, replaying
/// the start of every level and of the demo's generated mazes (made again in
/// `mazes`), then the top-difficulty mazes and the stress scenes
/// (`app::profile_scenes`), and logs the averages and maxima.
fn profile(mazes: &mut Mazes) {
    use hw::cpu_meter::count_instructions;
    let mut total = Costs::default();
    let mut picture = marble_rolling::matrix::Frame::<WIDTH, HEIGHT>::new();
    // The demo's levels, as `app::demo` numbers them.
    // No levels region on this board.
    let endless = Endless {
        from_region: 0,
        builtins: LEVELS.len(),
        reach: mazes.reach(),
        seeds: Seeds::Count,
    };
    for number in 0..LEVELS.len() + DEMO_MAZES {
        let level = match endless.stage(number) {
            Stage::Builtin(index) => LEVELS.get(index).copied(),
            Stage::Maze(args) => mazes.make(args).ok(),
            Stage::Region(_) => None,
        };
        let Some(Ok(mut player)) = level.map(|level| {
            Player::<WIDTH, HEIGHT, PILOT, EVENTS>::single(level, SYNTHETIC_TILT, true)
        }) else {
            continue;
        };
        let mut costs = Costs::default();
        while costs.frames < app::PROFILE_FRAMES {
            let (reading, pilot) = count_instructions(|| player.reading(AccelMg::LEVEL));
            let (phase, frame) =
                count_instructions(|| player.session_mut().frame_in::<EVENTS>(reading));
            let (_, render) = count_instructions(|| player.render());
            costs.add(pilot, frame, render);
            if phase != Phase::Playing {
                break;
            }
        }
        costs.log(player.level_name());
        log_budget_cuts(player.level_name(), player.session_mut());
        picture = player.render();
        total.merge(&costs);
    }
    total.log("all levels");
    // What the levels do not reach: three mazes at the top difficulty and the
    // stress scenes, profiled (not played in the demo) by the code every
    // board shares. Held to the same bound (`cargo xtask check-demo`).
    app::profile_scenes::<WIDTH, HEIGHT, PILOT, EVENTS, _, _>(mazes, |session, reading| {
        count_instructions(|| session.frame_in::<EVENTS>(reading))
    });
    let substeps = 1u64 << Player::<WIDTH, HEIGHT, PILOT, EVENTS>::CONFIG.substeps_log2;
    defmt::info!(
        "one game frame = {=u64} physics steps: {=u64} instructions on average (max {=u64}), {=u64} per physics step; autopilot {=u64}, render {=u64} per frame",
        substeps,
        total.average(total.frame),
        total.frame_max,
        total.average(total.frame) / substeps,
        total.average(total.pilot),
        total.average(total.render)
    );
    // The display's share, without its async plumbing: converting a frame
    // into bit planes, then one refresh of scan steps into the integrator.
    let mut scanner = Scanner::<WIDTH, HEIGHT>::new();
    let mut integrator = OnTimeIntegrator::<WIDTH, HEIGHT>::new();
    let (_, load) = count_instructions(|| scanner.load(&picture));
    let (_, scan) = count_instructions(|| {
        for _ in 0..Scanner::<WIDTH, HEIGHT>::STEPS_PER_REFRESH {
            integrator.feed(scanner.next_step());
        }
    });
    defmt::info!(
        "display: {=u64} instructions to load a frame, {=u64} to scan one refresh into the virtual matrix",
        load,
        scan
    );
}

/// How often the step's flight budget cut a marble's step (`physics::world::
/// FLIGHT_BUDGET`): `cargo xtask check-demo` wants none on a built-in level.
fn log_budget_cuts(
    what: &str,
    session: &mut marble_rolling::game::session::Session<'_, marble_rolling::physics::Fx>,
) {
    defmt::info!(
        "budget {=str}: {=u32} marble-steps cut",
        what,
        session.game_mut().world_mut().stats.budget_cuts
    );
}

/// Instruction totals of [`profile`].
#[derive(Default)]
struct Costs {
    frames: u32,
    pilot: u64,
    frame: u64,
    frame_max: u64,
    render: u64,
}

impl Costs {
    fn add(&mut self, pilot: u64, frame: u64, render: u64) {
        self.frames += 1;
        self.pilot += pilot;
        self.frame += frame;
        self.frame_max = self.frame_max.max(frame);
        self.render += render;
    }

    fn merge(&mut self, other: &Costs) {
        self.frames += other.frames;
        self.pilot += other.pilot;
        self.frame += other.frame;
        self.frame_max = self.frame_max.max(other.frame_max);
        self.render += other.render;
    }

    fn average(&self, sum: u64) -> u64 {
        sum / u64::from(self.frames.max(1))
    }

    fn log(&self, what: &str) {
        defmt::info!(
            "profile {=str}: {=u32} frames, instructions per frame: physics {=u64} (max {=u64}), autopilot {=u64}, render {=u64}",
            what,
            self.frames,
            self.average(self.frame),
            self.frame_max,
            self.average(self.pilot),
            self.average(self.render)
        );
    }
}
