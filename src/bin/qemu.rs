//! Marble Rolling firmware for QEMU's `mps2-an386` (Cortex-M4F).
//!
//! `cargo qemu` plays on the terminal (UART0); `cargo qemu -- --demo` runs the
//! deterministic headless demo, reports the CPU load and exits 0. The runner
//! is `tools/qemu-run.sh`; it tells the firmware its mode on the semihosting
//! command line (see `marble_rolling::board::qemu::Options`).
//!
//! The tasks below are thin wrappers: the logic is in `marble_rolling::app`.
#![no_std]
#![no_main]

use core::sync::atomic::{AtomicBool, Ordering};

use defmt_semihosting as _;
use marble_rolling::app::{self, DemoInput, GameExit, TerminalInput};
use marble_rolling::board::qemu::cpu_meter::LoadReport;
use marble_rolling::board::qemu::virtual_matrix::{restore_terminal, VirtualMatrix};
use marble_rolling::board::qemu::Options;

#[path = "../board/qemu/hw.rs"]
mod hw;

use hw::uart::{UartConsole, UartRx};

/// Headless runs log the perceived matrix every this many refreshes (4 Hz).
const LOG_MATRIX_EVERY: u32 = app::REFRESH_HZ / 4;

#[cortex_m_rt::entry]
fn main() -> ! {
    let Some(mut core) = cortex_m::Peripherals::take() else {
        hw::fatal("core peripherals already taken");
    };
    // First, so that log timestamps start at 0.
    hw::start_time(&mut core.SYST);
    let options = hw::options();
    defmt::info!("Marble Rolling on QEMU mps2-an386: {}", options);

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
        let game = game(options);
        match (display, game) {
            (Ok(display), Ok(game)) => {
                spawner.spawn(display);
                spawner.spawn(game);
            }
            _ => hw::fatal("cannot spawn tasks"),
        }
        let input = if options.interactive {
            terminal_input().map(|token| spawner.spawn(token))
        } else {
            demo_input().map(|token| spawner.spawn(token))
        };
        if input.is_err() {
            hw::fatal("cannot spawn the input task");
        }
    })
}

#[embassy_executor::task]
async fn terminal_input() -> ! {
    app::input_task(&mut TerminalInput::new(UartRx)).await
}

#[embassy_executor::task]
async fn demo_input() -> ! {
    app::input_task(&mut DemoInput::new()).await
}

#[embassy_executor::task]
async fn display(interactive: bool) -> ! {
    if interactive {
        app::display_task(&mut VirtualMatrix::new(Some(UartConsole), 0)).await
    } else {
        app::display_task(&mut VirtualMatrix::<UartConsole>::new(
            None,
            LOG_MATRIX_EVERY,
        ))
        .await
    }
}

#[embassy_executor::task]
async fn game(options: Options) {
    let start = hw::cpu_meter::sample();
    let demo_steps = options.demo_steps.unwrap_or(app::DEMO_STEPS);
    let limit = (!options.interactive).then_some(demo_steps);
    let exit = app::game_task(limit).await;
    let end = hw::cpu_meter::sample();
    match exit {
        GameExit::Quit => {
            restore_terminal(&mut UartConsole);
            defmt::info!("quit");
        }
        GameExit::StepLimit => {
            defmt::info!("demo finished after {=u32} steps", demo_steps);
        }
    }
    if options.interactive {
        // No -icount: the CPU meter's figures would mean nothing.
        hw::exit(0)
    }
    let calibration = hw::cpu_meter::calibration();
    let mut state = app::GameState::new();
    let tilt = app::Tilt::from_xz(-300, 0);
    let (_, instructions) = hw::cpu_meter::count_instructions(|| app::game_tick(&mut state, tilt));
    defmt::info!(
        "one placeholder game_tick: {=u64} instructions",
        instructions
    );
    match LoadReport::between(&calibration, start, end) {
        Some(load) => {
            defmt::info!(
                "cpu load: {=u64} busy instructions in {=u64} us of firmware time = {=u64} instructions/s = {=u64}.{=u64:02} % of a 64 MHz Cortex-M4",
                load.busy_instructions,
                load.firmware_us,
                load.instructions_per_second,
                load.centipercent_of_64mhz / 100,
                load.centipercent_of_64mhz % 100,
            );
        }
        None => defmt::warn!("cpu load: no time elapsed"),
    }
    hw::exit(0)
}

#[panic_handler]
fn panic(info: &core::panic::PanicInfo) -> ! {
    static PANICKED: AtomicBool = AtomicBool::new(false);
    cortex_m::interrupt::disable();
    // A panic inside the logger (or a second panic) must not recurse.
    if !PANICKED.swap(true, Ordering::SeqCst) {
        defmt::error!("panic: {}", defmt::Display2Format(info));
    }
    hw::exit(101)
}
