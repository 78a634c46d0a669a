//! Physics cost on the target ISA: QEMU `mps2-an386` (Cortex-M4F), counted
//! instruction by instruction under `-icount shift=7,align=off,sleep=off`.
//!
//! Runs the study's scene suite ([`marble_rolling::study`]) for every scene ×
//! backend × step rate, plus the per-effect variants, and prints one defmt line
//! per run:
//!
//! ```text
//! BENCH <scene> <backend> <variant> <step_log2> <steps> <instructions> <hash> <contacts> <collisions>
//! ```
//!
//! `cargo accuracy` runs it (through `cargo xtask bench-m4`, which decodes the
//! defmt log) and parses those lines; by hand: `cargo xtask bench-m4
//! [--backends=MASK] [--rates=MASK]`.
//!
//! Options on the semihosting command line: `--backends=MASK` (bit n selects
//! `study::BACKENDS[n]`), `--rates=MASK` (bit k selects 2^k steps/s; bit 0
//! selects event stepping, `study::EVENTS_LOG2`, printed as `<step_log2>` 0:
//! its `<steps>` are frames, 128 per simulated second), `--scenes=MASK` (bit n
//! selects `study::SceneId` number n: incline, bounce, maze, corner) and
//! `--variants=0` (no per-effect variants: what `cargo xtask qemu-profile
//! --bench` traces).
//!
//! The instruction counter is the board's TIMER0 (25 MHz, 3.2 ticks per
//! instruction at shift=7), calibrated against a NOP loop of known length
//! (`hw::cpu_meter`); each count covers a whole 10 s scene run (all steps and
//! the per-frame tilt updates), interrupts off.
#![no_std]
#![no_main]

use defmt_semihosting as _;
use marble_rolling::study::{bench_one, bench_plan, Scene, BACKENDS};

use marble_board_runtime::args::number_option as mask_option;
use marble_qemu as hw;

#[cortex_m_rt::entry]
fn main() -> ! {
    hw::clock::start();
    let cal = hw::cpu_meter::calibrate();
    defmt::info!(
        "CALIBRATION {=u32} {=u32} {=u64} {=bool} {=u32}",
        cal.instructions,
        cal.ticks,
        cal.milliticks_per_instruction(),
        cal.matches_icount(),
        cal.overhead_ticks
    );
    // Self-check of the counter: an empty closure costs (almost) nothing.
    let (_, empty) = hw::cpu_meter::count_instructions(|| core::hint::black_box(0u32));
    defmt::info!("EMPTY {=u64}", empty);
    let backends = mask_option("--backends", (1 << BACKENDS.len()) - 1);
    let rates = mask_option("--rates", u32::MAX);
    let scenes = mask_option("--scenes", u32::MAX);
    let variants = mask_option("--variants", 1) != 0;
    bench_plan(backends, rates, |item| {
        if scenes & (1 << item.scene as u32) == 0 || (item.variant.is_some() && !variants) {
            return;
        }
        let result = bench_one(&item, &mut |f| hw::cpu_meter::count_instructions(f).1);
        match result {
            Some(r) => defmt::info!(
                "BENCH {=str} {=str} {=str} {=u32} {=u32} {=u64} {=u64} {=u32} {=u32}",
                Scene::get(item.scene).name,
                BACKENDS[item.backend],
                item.variant_name(),
                item.step_log2,
                r.steps,
                r.instructions,
                r.hash,
                r.contacts,
                r.collisions
            ),
            None => defmt::error!(
                "setup failed: {} {=str}",
                item.scene,
                BACKENDS[item.backend]
            ),
        }
    });
    defmt::info!("DONE");
    hw::exit(0)
}
