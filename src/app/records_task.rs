//! The records task: the best times in flash ([`Records`]), read for the
//! game's status and offered each win the player (not the autopilot) makes.

use embedded_storage_async::nor_flash::NorFlash;

use super::links::{Bests, Links};
#[cfg(feature = "defmt")]
use super::FRAME_HZ;
use crate::game::levels::LEVELS;
use crate::records::{Offer, Records};

/// Keeps the best times (feature `records`): reads every level's record into
/// `Links::bests`, then offers each `Win` from `Links::wins` to
/// `records` and, on a new record, tells the game (`Links::new_record`).
/// `written` runs after each update that wrote (QEMU saves its flash image to
/// a host file there). Flash errors are logged and the game goes on without
/// the record.
pub async fn records_task<F: NorFlash, const W: usize, const H: usize>(
    links: &Links<W, H>,
    records: &mut Records<F>,
    mut written: impl FnMut(&mut F),
) -> ! {
    let mut bests: Bests = [None; LEVELS.len()];
    read_bests(records, &mut bests).await;
    links.bests.set(bests);
    loop {
        let win = links.wins.receive().await;
        let offer = records.offer(win.level, win.frames).await;
        #[cfg(feature = "defmt")]
        log_offer(win, offer);
        if let Ok(Offer::Kept { .. }) = offer {
            continue;
        }
        // Something was written (a record, or an erase of a corrupted
        // region): every level's record again, as the flash now holds them.
        read_bests(records, &mut bests).await;
        links.bests.set(bests);
        if let Ok(Offer::New { .. }) = offer {
            links.new_record.signal(win.level);
        }
        written(records.flash());
    }
}

/// Every level's record into `bests` (one that cannot be read: none).
async fn read_bests<F: NorFlash>(records: &mut Records<F>, bests: &mut Bests) {
    for (level, best) in bests.iter_mut().enumerate() {
        *best = match records.best(level as u8).await {
            Ok(b) => b,
            Err(e) => {
                #[cfg(feature = "defmt")]
                defmt::warn!("records: level {=usize}: {=str}", level + 1, e.as_str());
                let _ = e;
                None
            }
        };
    }
}

/// The record news in the log: the time in seconds with hundredths.
#[cfg(feature = "defmt")]
fn log_offer(win: super::links::Win, offer: Result<Offer, crate::records::RecordError>) {
    let name = LEVELS
        .get(usize::from(win.level))
        .map_or("?", |level| level.info.name);
    let cs = |frames: u32| frames.saturating_mul(100) / FRAME_HZ;
    match offer {
        Ok(Offer::New {
            previous: Some(previous),
        }) => defmt::info!(
            "new record: level {=u8} {=str} in {=u32}.{=u32:02} s (was {=u32}.{=u32:02} s)",
            win.level + 1,
            name,
            cs(win.frames) / 100,
            cs(win.frames) % 100,
            cs(previous) / 100,
            cs(previous) % 100
        ),
        Ok(Offer::New { previous: None }) => defmt::info!(
            "new record: level {=u8} {=str} in {=u32}.{=u32:02} s (the first)",
            win.level + 1,
            name,
            cs(win.frames) / 100,
            cs(win.frames) % 100
        ),
        Ok(Offer::Kept { best }) => defmt::info!(
            "level {=u8} {=str} in {=u32}.{=u32:02} s: the record stays {=u32}.{=u32:02} s",
            win.level + 1,
            name,
            cs(win.frames) / 100,
            cs(win.frames) % 100,
            cs(best) / 100,
            cs(best) % 100
        ),
        Err(e) => defmt::warn!("records: {=str}", e.as_str()),
    }
}
