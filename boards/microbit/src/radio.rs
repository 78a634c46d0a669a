//! The radio for racing a friend (`app::race_task`): the nRF52833's RADIO
//! through embassy-nrf's `radio::ieee802154` driver, moving the race's packets
//! between the air and the race task ([`Air`]). Wiring only: the
//! framing (a group byte before each packet) is `race::air`, the protocol
//! `race`, both host-tested.
//!
//! Why IEEE 802.15.4: it is the one mode embassy-nrf 0.11 drives this radio
//! in (its `radio` module has `ieee802154` and nothing else for the
//! nRF52833; the chip's BLE and proprietary Nordic modes have no driver
//! there). A frame carries 125 bytes (`Packet::CAPACITY`) at 250 kbit/s on
//! one of 16 channels (11 to 26), and the hardware adds and checks a CRC of
//! its own, so most garbled frames never reach the race's CRC. A race
//! packet is at most 124 bytes (`race::MAX_PACKET`): one frame with its
//! group byte.
//!
//! The radio is half duplex: it listens until the race task has a packet to
//! send, sends it after a clear channel assessment (a busy channel drops the
//! packet, which the protocol repeats), then listens again. Proven on
//! hardware only by reading (docs/boards.md): no emulator here has the
//! nRF52's radio.

use embassy_futures::select::{select3, Either3};
use embassy_nrf::gpio::Input;
use embassy_nrf::pac;
use embassy_nrf::radio::ieee802154::{Packet, Radio};
use embassy_nrf::wdt::WatchdogHandle;
use embassy_time::{Duration, Timer};
use marble_rolling::app::{Air, AirPacket};
use marble_rolling::input::race_setup::Tuning;
use marble_rolling::race::air::{self, AirCounters, AIR_FRAME};

/// Transmit power, dBm (the driver's default; one it accepts on the nRF52833).
const TX_POWER_DBM: i8 = 0;
/// The crystal oscillator starts in about 0.4 ms (nRF52833 PS, HFXO): given
/// ten times that before the radio goes on without it.
const HFXO_POLLS: u32 = 40;
/// Released for this long, A is no longer bouncing (the buttons' debounce is
/// 30 ms).
const RELEASE_SETTLE_MS: u32 = 100;
/// Frames sent between two log lines of the counters.
const LOG_EVERY: u32 = 1024;

/// The wake-up from System OFF (a button press after idle sleep) is this
/// reset: the button that woke the board may still be held, and holding A at
/// power-on asks for a race. Clears the reason, so a later reset does not
/// see it.
pub fn woke_from_system_off() -> bool {
    let reasons = pac::POWER.resetreas().read();
    pac::POWER.resetreas().write(|w| w.set_off(true));
    reasons.off()
}

/// Starts the 32 MHz crystal, which the radio needs for its frequency
/// accuracy (embassy-nrf starts the board on the internal RC oscillator,
/// enough for the game); `false` if it did not start in time.
async fn start_hfxo() -> bool {
    let clock = pac::CLOCK;
    clock.events_hfclkstarted().write_value(0);
    clock.tasks_hfclkstart().write_value(1);
    for _ in 0..HFXO_POLLS {
        if clock.events_hfclkstarted().read() != 0 {
            return true;
        }
        Timer::after(Duration::from_micros(100)).await;
    }
    false
}

/// Tunes the radio to `tuning`'s channel; `false` if the channel is not one
/// of 802.15.4's 11 to 26 (the driver would panic on it).
fn tune(radio: &mut Radio<'static>, tuning: Tuning) -> bool {
    if !(11..=26).contains(&tuning.channel) {
        return false;
    }
    radio.set_channel(tuning.channel);
    true
}

/// Moves packets between the air and `air` for ever, on the channel and
/// group the race task chose (nothing before the first choice).
pub async fn run(mut radio: Radio<'static>, air: &'static Air) -> ! {
    let mut tuning = air.tuning.wait().await;
    if !start_hfxo().await {
        defmt::error!("radio: the 32 MHz crystal did not start; racing on the RC oscillator");
    }
    radio.set_transmission_power(TX_POWER_DBM);
    let mut tuned = tune(&mut radio, tuning);
    let mut rx = Packet::new();
    let mut tx = Packet::new();
    let mut out = [0u8; AIR_FRAME];
    let mut counters = AirCounters::default();
    loop {
        if !tuned {
            defmt::error!("radio: channel {=u8} is not 11 to 26", tuning.channel);
            tuning = air.tuning.wait().await;
            tuned = tune(&mut radio, tuning);
            continue;
        }
        match select3(
            radio.receive(&mut rx),
            air.outgoing.receive(),
            air.tuning.wait(),
        )
        .await
        {
            Either3::First(Ok(())) => received(&rx, tuning.group, air, &mut counters),
            Either3::First(Err(_)) => counters.crc = counters.crc.saturating_add(1),
            Either3::Second(packet) => {
                let sent = send(
                    &mut radio,
                    &mut tx,
                    &mut out,
                    tuning.group,
                    &packet,
                    &mut counters,
                )
                .await;
                if sent && counters.sent.is_multiple_of(LOG_EVERY) {
                    defmt::info!("radio: {}", counters);
                }
            }
            Either3::Third(t) => {
                tuning = t;
                tuned = tune(&mut radio, tuning);
                defmt::info!("radio: {}; now channel {=u8}", counters, tuning.channel);
            }
        }
    }
}

/// Hands the packet in `rx` to the race task if it is the group's.
fn received(rx: &Packet, group: u8, air: &Air, counters: &mut AirCounters) {
    // The length comes from the frame's header as received: checked before
    // the payload is sliced by it.
    if rx.len() > Packet::CAPACITY {
        counters.other = counters.other.saturating_add(1);
        return;
    }
    match air::unframe(group, rx) {
        Ok(packet) => match AirPacket::from_slice(packet) {
            Ok(p) => {
                counters.received = counters.received.saturating_add(1);
                if air.incoming.try_send(p).is_err() {
                    counters.overflow = counters.overflow.saturating_add(1);
                }
            }
            Err(_) => counters.other = counters.other.saturating_add(1),
        },
        Err(_) => counters.other = counters.other.saturating_add(1),
    }
}

/// Sends `packet` as a frame of `group`; whether it went.
async fn send(
    radio: &mut Radio<'static>,
    tx: &mut Packet,
    out: &mut [u8; AIR_FRAME],
    group: u8,
    packet: &[u8],
    counters: &mut AirCounters,
) -> bool {
    let Some(frame) = air::frame(group, packet, out) else {
        counters.not_sent = counters.not_sent.saturating_add(1);
        return false;
    };
    // `frame` is at most AIR_FRAME, the driver's capacity.
    tx.copy_from_slice(frame);
    match radio.try_send(tx).await {
        Ok(()) => {
            counters.sent = counters.sent.saturating_add(1);
            true
        }
        Err(_) => {
            counters.not_sent = counters.not_sent.saturating_add(1);
            false
        }
    }
}

/// Waits until button `a`, held at power-on to ask for a race, is released
/// and has settled, petting the watchdog meanwhile (its task is not running
/// yet): the buttons report a press on its release, which the chooser would
/// take for its first.
pub async fn released(a: &Input<'static>, wdt: &mut Option<WatchdogHandle>) {
    let mut settled = 0;
    while settled < RELEASE_SETTLE_MS / 10 {
        if let Some(handle) = wdt {
            handle.pet();
        }
        settled = if a.is_low() { 0 } else { settled + 1 };
        Timer::after(Duration::from_millis(10)).await;
    }
}
