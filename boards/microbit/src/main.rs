//! Marble Rolling firmware for the BBC micro:bit v2 (nRF52833).
//!
//! `cargo microbit` builds it and runs it with `probe-rs run --chip nRF52833_xxAA`
//! (defmt log over RTT). Wiring only: the tasks are the shared ones from
//! `marble_rolling::app`, fed by the micro:bit input (LSM303AGR + buttons)
//! and drawing on the 5×5 matrix (`src/hw.rs`, `src/sensor.rs`, `src/sleep.rs` and `src/storage.rs` here, and `marble_rolling::board::microbit`).
//!
//! Executors:
//! * thread mode: input (accelerometer + buttons, 100 Hz), the game
//!   (`app::play_task`, or `app::race_task` with A held at power-on, and then
//!   the radio task, `src/radio.rs`), and the watchdog task;
//! * EGU0_SWI0 interrupt (priority P6, above thread mode): the display, so
//!   game computation can never stretch a BCM slice.
//!
//! Watchdog (1 s, paused while a debugger halts the CPU): one channel, petted
//! by the watchdog task only when every task has proved since the last pet
//! that it runs (`board::Heartbeats`, `board::WatchdogGate`): input beats
//! once a poll, the display on every scan step, the game each time it is
//! polled, the sound at each note and the records at each flash operation
//! (those two are excused while they wait for a sound or a win). A loop petting on its own would miss a task parked forever at an
//! `await`; this way any stalled task, or a task hogging the thread executor
//! (the watchdog task runs there too), stops the pets and resets the board.
//! A panic halts in panic-probe and the watchdog restarts the board.

#![no_std]
#![no_main]

use defmt_rtt as _;
use panic_probe as _;

mod hw;
mod radio;
mod sensor;
mod sleep;
mod storage;

use core::pin::pin;

use embassy_executor::{InterruptExecutor, Spawner};
use embassy_nrf::interrupt;
use embassy_nrf::interrupt::{InterruptExt, Priority};
use embassy_nrf::twim;
use embassy_nrf::wdt::{self, Watchdog, WatchdogHandle};
use embassy_nrf::{bind_interrupts, peripherals};
use embassy_time::{Duration, Ticker};
use lsm303agr::Lsm303agr;
use marble_board_runtime::heartbeat::poll_beating;

use marble_rolling::app::{self, Links};
use marble_rolling::board::levels_region;
use marble_rolling::board::microbit::{self as board, Heartbeats, Task, Verdict, WatchdogGate};
use marble_rolling::game::endless::{MazeSlot, Seeds};
use marble_rolling::input::race_setup;
use marble_rolling::input::tilt::TiltConfig;
use marble_rolling::matrix::Frame;
use marble_rolling::player::power_on::{self, PowerOn};

bind_interrupts!(pub struct Irqs {
    TWISPI0 => twim::InterruptHandler<peripherals::TWISPI0>;
    RADIO => embassy_nrf::radio::InterruptHandler<peripherals::RADIO>;
});

/// The race task's packets to and from the radio task.
static AIR: app::Air = app::Air::new();

/// The radio (racing only: A held at power-on).
#[embassy_executor::task]
async fn radio(radio: embassy_nrf::radio::ieee802154::Radio<'static>) -> ! {
    radio::run(radio, &AIR).await
}

/// The links between the tasks.
static LINKS: Links<{ board::WIDTH }, { board::HEIGHT }> = Links::new();

/// Each task's proof that it runs, read by the watchdog task.
static HEARTBEATS: Heartbeats = Heartbeats::new();

/// Checks without a pet after which the watchdog task logs who is stalled
/// (half the watchdog period).
const STALL_LOG_CHECKS: u16 = 5;

/// Checks between two looks at the stack's high-water mark (10 s).
const STACK_LOG_CHECKS: u32 = 100;

/// No autopilot on the micro:bit: no button combination is left for it, and
/// leaving it out saves about 6 KiB of flash.
const PILOT: bool = false;

/// The stepper every board plays (`GameConfig::DEFAULT`, events: no speed cap,
/// no sinking into walls). Its code (about 18 KiB here) fits the v2's 144 KiB
/// flash budget (`cargo xtask size-report`, which reads
/// [`MARBLE_STEPPING_EVENTS`] back from the ELF).
const EVENTS: bool = marble_rolling::game::rules::DEFAULT_EVENTS;

/// The stepping [`EVENTS`] links, named in the ELF for `cargo xtask
/// size-report` to print (`xtask/src/size.rs` reads this symbol's byte:
/// 1 events, 0 fixed). One byte of flash; `#[used]` keeps it though nothing
/// reads it here.
#[used]
#[no_mangle]
static MARBLE_STEPPING_EVENTS: u8 = EVENTS as u8;

/// Runs the display above thread mode.
static EXECUTOR_DISPLAY: InterruptExecutor = InterruptExecutor::new();

#[interrupt]
unsafe fn EGU0_SWI0() {
    // SAFETY: called only from this interrupt handler, after `start` below
    // (the interrupt is unmasked by `start`).
    unsafe { EXECUTOR_DISPLAY.on_interrupt() }
}

#[embassy_executor::task]
async fn display(mut matrix: hw::Matrix) -> ! {
    app::display_task(&LINKS, &mut matrix).await
}

/// The game's sounds on the speaker (hw::Speaker).
#[embassy_executor::task]
async fn sound(mut speaker: hw::Speaker) -> ! {
    app::sound_task(&LINKS, &mut speaker).await
}

#[embassy_executor::task]
async fn input(mut input: sensor::MicrobitInput) -> ! {
    app::input_task(&LINKS, &mut input).await
}

/// Room for the endless run's generated maze ([`board::MAZE_REACH`]).
type Mazes = MazeSlot<{ board::MAZE_REACH.words() }, { board::MAZE_REACH.text_bytes() }>;

/// The game; first the self-test when B was held at power-on
/// (`app::power_on::self_test`), until A. The generated mazes after the built-in
/// levels take their seeds from `seed`, drawn at power-up; each level's
/// ghost is raced from `ghosts`' store. With `race` (A held at power-on) the
/// race task instead, for ever (its maze in the same slot, its link of the
/// lean sizes: the 16 KiB RAM budget).
#[embassy_executor::task]
async fn game(
    self_test: bool,
    level: u8,
    seed: u32,
    ghosts: Option<storage::GhostsStore>,
    race: bool,
) {
    if self_test {
        defmt::info!("self-test: LEDs one by one, brightness levels, then the tilt dot; A to play");
        let test = pin!(app::power_on::self_test(&LINKS));
        poll_beating(|| HEARTBEATS.beat(Task::Game), test).await;
    }
    // The player's levels (cargo xtask hex --level), played first, parsed
    // into the maze slot in turn; one log line says what the region holds or
    // why it is ignored.
    let region = levels_region::at_boot(hw::levels_region());
    let mut mazes = Mazes::new(board::MAZE_REACH).with_region(region);
    if race {
        use marble_rolling::race::stream::{
            LEAN_EARLY_BLOCKS, LEAN_INBOX_READINGS, LEAN_OUT_BLOCKS,
        };
        let race = pin!(app::race_task::<
            { board::WIDTH },
            { board::HEIGHT },
            LEAN_OUT_BLOCKS,
            LEAN_INBOX_READINGS,
            LEAN_EARLY_BLOCKS,
            _,
            _,
        >(&LINKS, &AIR, &mut mazes, seed));
        poll_beating(|| HEARTBEATS.beat(Task::Game), race).await;
    }
    // After the race's block, and awaited at one place only: the race never
    // returns, so the levels' future (with the ghosts' kit and its two run
    // buffers) takes the room the race's has in this task's (the kit in a
    // static of its own would be 1.3 KB more of static RAM).
    play_levels(level, seed, &mut mazes, ghosts).await
}

/// The levels for ever, from `level` (the generated mazes' seeds from
/// `seed`), each level's ghost raced from `ghosts`' store.
async fn play_levels(
    level: u8,
    seed: u32,
    mazes: &mut Mazes,
    ghosts: Option<storage::GhostsStore>,
) -> ! {
    // Made here, in this future: written in place, never moved through a
    // stack frame.
    #[cfg_attr(not(feature = "ghosts"), allow(unused_mut, unused_variables))]
    let mut kit = storage::kit(ghosts);
    loop {
        // The micro:bit never sends Quit; restart the game if it ever returns.
        // The game loop is app's (play only: the v2 has no demo); being
        // polled (every frame tick, paused or not) is its heartbeat.
        // In a block of its own: gone before the sleep's await below, the
        // game's future is live at one await only, so it shares its room
        // with the sleep's (held at two, it would be kept beside the race's
        // too: 2.4 KB more of static RAM).
        let exit = {
            #[cfg(feature = "ghosts")]
            let game = pin!(app::play_task::<
                { board::WIDTH },
                { board::HEIGHT },
                PILOT,
                EVENTS,
                _,
                _,
            >(
                &LINKS,
                TiltConfig::SENSOR,
                level,
                Seeds::Drawn(seed),
                mazes,
                kit.as_mut()
            ));
            #[cfg(not(feature = "ghosts"))]
            let game = pin!(app::play_task::<
                { board::WIDTH },
                { board::HEIGHT },
                PILOT,
                EVENTS,
                _,
                _,
            >(
                &LINKS,
                TiltConfig::SENSOR,
                level,
                Seeds::Drawn(seed),
                mazes
            ));
            poll_beating(|| HEARTBEATS.beat(Task::Game), game).await
        };
        if let app::GameExit::Asleep { level } = exit {
            // The input task powers the accelerometer down and enters
            // System OFF (sleep::system_off).
            sleep::request_sleep(level).await;
        }
        defmt::warn!("game_task returned: {}", exit);
    }
}

/// The best times in [`board::RECORDS`].
#[embassy_executor::task]
async fn records(mut records: marble_rolling::records::Records<storage::RecordsFlash>) -> ! {
    app::records_task(&LINKS, &mut records, |_| {}).await
}

/// Pets the watchdog whenever every task has beaten since the last pet.
#[embassy_executor::task]
async fn watchdog(mut handle: WatchdogHandle) -> ! {
    let mut gate = WatchdogGate::new(HEARTBEATS.snapshot());
    let mut ticker = Ticker::every(Duration::from_millis(board::WATCHDOG_CHECK_MS));
    let (mut stack, mut checks) = (hw::stack::Meter::new(), 0u32);
    loop {
        ticker.next().await;
        checks = checks.wrapping_add(1);
        if checks % STACK_LOG_CHECKS == 1 {
            stack.log_growth();
        }
        match gate.check(HEARTBEATS.snapshot()) {
            Verdict::Pet => handle.pet(),
            Verdict::Wait { stalled, checks } => {
                if checks == STALL_LOG_CHECKS {
                    defmt::error!("watchdog: no pet, stalled: {}", stalled);
                }
            }
        }
    }
}

/// Starts the watchdog with one channel (the watchdog task's).
fn start_watchdog(wdt: embassy_nrf::Peri<'static, peripherals::WDT>) -> Option<WatchdogHandle> {
    let mut config = wdt::Config::default();
    config.timeout_ticks = board::WATCHDOG_TIMEOUT_TICKS;
    config.action_during_debug_halt = wdt::HaltConfig::Pause;
    match Watchdog::try_new::<_, 1>(wdt, config) {
        Ok((_watchdog, [handle])) => Some(handle),
        Err(_) => {
            // Already running with another configuration (it survives a soft
            // reset, e.g. an older firmware's): it will reset us, and the
            // next boot configures it.
            defmt::error!("watchdog already running with another configuration");
            None
        }
    }
}

#[embassy_executor::main]
async fn main(spawner: Spawner) {
    // Before anything deep uses the stack.
    hw::stack::paint();
    let p = embassy_nrf::init(Default::default());
    defmt::info!("Marble Rolling on micro:bit v2");

    let mut wdt = start_watchdog(p.WDT);

    // LED matrix: rows P0.21, P0.22, P0.15, P0.24, P0.19; columns P0.28,
    // P0.11, P0.31, P1.05, P0.30.
    let matrix = hw::Matrix::new(
        [
            hw::Matrix::row_pin(p.P0_21),
            hw::Matrix::row_pin(p.P0_22),
            hw::Matrix::row_pin(p.P0_15),
            hw::Matrix::row_pin(p.P0_24),
            hw::Matrix::row_pin(p.P0_19),
        ],
        [
            hw::Matrix::col_pin(p.P0_28),
            hw::Matrix::col_pin(p.P0_11),
            hw::Matrix::col_pin(p.P0_31),
            hw::Matrix::col_pin(p.P1_05),
            hw::Matrix::col_pin(p.P0_30),
        ],
        &HEARTBEATS,
    );
    interrupt::EGU0_SWI0.set_priority(Priority::P6);
    let display_spawner = EXECUTOR_DISPLAY.start(interrupt::EGU0_SWI0);
    match display(matrix) {
        Ok(token) => display_spawner.spawn(token),
        Err(_) => defmt::error!("display task already running"),
    }

    // Buttons A P0.14, B P0.23: what is held now chooses (player::power_on).
    let (button_a, button_b) = (
        sensor::MicrobitInput::button_pin(p.P0_14),
        sensor::MicrobitInput::button_pin(p.P0_23),
    );
    let held = (button_a.is_low(), button_b.is_low());
    let choice = power_on::power_on(held.0, held.1);
    defmt::info!("power-on: {}", choice);
    let race = race_setup::race_at_power_on(held.0, held.1, radio::woke_from_system_off());
    if race {
        radio::released(&button_a, &mut wdt).await;
    }

    // The best times (board::RECORDS) and the ghosts (board::GHOSTS), one
    // NVMC shared (storage).
    let mut stores = storage::open(p.NVMC, &HEARTBEATS);
    if choice == PowerOn::ClearRecords {
        // The app's question until a button answers (A clears every best
        // time and ghost, B or 10 s of nothing keeps them), petting the
        // watchdog meanwhile (its task is not running yet).
        defmt::info!("A+B at power-on: clear the best times? A yes, B no");
        let clear = app::power_on::ask_clear(
            &LINKS,
            || (button_a.is_low(), button_b.is_low()),
            || {
                if let Some(handle) = &mut wdt {
                    handle.pet();
                }
            },
        )
        .await;
        if clear {
            storage::clear(&mut stores).await;
        } else {
            defmt::info!("records kept");
        }
        LINKS.frames.signal(Frame::new());
    }

    // Internal I²C: SDA P0.16, SCL P0.08. The driver writes register
    // addresses from flash, so the bus gives its TWIM a RAM copy buffer
    // (board::TWIM_COPY_BUFFER_BYTES), a deadline per transfer and a bus
    // clear (sensor::Bus).
    let bus = sensor::bus(p.TWISPI0, p.P0_16.into(), p.P0_08.into());
    let sensor = Lsm303agr::new_with_i2c(bus);
    let input_dev = sensor::MicrobitInput::new(sensor, button_a, button_b, &HEARTBEATS);

    // Speaker: P0.00, PWM0.
    let speaker = hw::Speaker::new(p.PWM0, p.P0_00, &HEARTBEATS);

    match input(input_dev) {
        Ok(token) => spawner.spawn(token),
        Err(_) => defmt::error!("input task already running"),
    }
    // The seeds of this power-up's generated mazes, from the RNG's thermal
    // noise (four bytes: well under a millisecond, before the game starts).
    let seed = embassy_nrf::rng::Rng::new_blocking(p.RNG).blocking_next_u32();
    defmt::info!("generated mazes: seeds from {=u32}", seed);
    // After a wake-up from System OFF: the level it fell asleep on.
    match game(
        choice == PowerOn::SelfTest,
        sleep::level_after_reset(),
        seed,
        stores.ghosts,
        race,
    ) {
        Ok(token) => spawner.spawn(token),
        Err(_) => defmt::error!("game task already running"),
    }
    if race {
        defmt::info!("power-on: A held: racing (A counts, B chooses: channel, then group)");
        let air = embassy_nrf::radio::ieee802154::Radio::new(p.RADIO, Irqs);
        match radio(air) {
            Ok(token) => spawner.spawn(token),
            Err(_) => defmt::error!("radio task already running"),
        }
    }
    match sound(speaker) {
        Ok(token) => spawner.spawn(token),
        Err(_) => defmt::error!("sound task already running"),
    }
    match stores.records {
        Some(store) => match records(store) {
            Ok(token) => spawner.spawn(token),
            Err(_) => defmt::error!("records task already running"),
        },
        None => defmt::error!("records: no store, no records task"),
    }
    if let Some(handle) = wdt {
        match watchdog(handle) {
            Ok(token) => spawner.spawn(token),
            Err(_) => defmt::error!("watchdog task already running"),
        }
    }
}
