//! The NVMC shared by the best times (the records task) and the ghosts (the
//! game task): one `RefCell` over the flash, a region for each store
//! (`marble_rolling::board::microbit::storage`, the library's feature
//! `shared-flash`, host-tested there). Wiring only.
//!
//! Without the `ghosts` feature (on by default; `--no-default-features`
//! builds the v2 of before, best times and no ghost) the records have the
//! NVMC to themselves: the same names, a store that is never there.

#[cfg(feature = "ghosts")]
mod shared {
    use core::cell::RefCell;

    use embassy_nrf::nvmc::Nvmc;
    use embassy_nrf::{peripherals, Peri};
    use marble_rolling::app::GhostKit;
    use marble_rolling::board::microbit::storage::{self, local, Region};
    use marble_rolling::board::microbit::{self as board, Heartbeats};
    use marble_rolling::records::{Ghosts, Records};

    use crate::hw::WatchedFlash;

    /// One store's region of the NVMC, blocking (the CPU waits on a page
    /// erase, about 85 ms, between levels only), its task yielding after
    /// each erase and write.
    pub type Part = Region<'static, Nvmc<'static>>;

    /// The records' flash, each operation a heartbeat of the records task
    /// ([`WatchedFlash`]).
    pub type RecordsFlash = WatchedFlash<Part>;

    /// The ghosts' flash: the records' type, unwatched.
    pub type GhostsFlash = WatchedFlash<Part>;

    /// The ghosts and the game task's two run buffers of
    /// [`board::GHOST_BYTES`].
    pub type Kit = GhostKit<GhostsFlash, { board::GHOST_BYTES }>;

    /// The ghosts' store, which the game task makes its [`Kit`] of.
    pub type GhostsStore = Ghosts<GhostsFlash>;

    /// The stores over the NVMC; a store whose region is not whole pages is
    /// `None` (logged).
    pub struct Stores {
        /// The best times in [`board::RECORDS`].
        pub records: Option<Records<RecordsFlash>>,
        /// The ghosts in [`board::GHOSTS`].
        pub ghosts: Option<Ghosts<GhostsFlash>>,
    }

    /// Opens both stores over the NVMC.
    pub fn open(nvmc: Peri<'static, peripherals::NVMC>, heartbeats: &'static Heartbeats) -> Stores {
        let none = Stores {
            records: None,
            ghosts: None,
        };
        // The cell lives as long as the tasks that borrow it: a static, filled
        // once here (the NVMC peripheral can be taken only once).
        let Some(flash) = cortex_m::singleton!(
            : RefCell<Nvmc<'static>> = RefCell::new(Nvmc::new(nvmc))
        ) else {
            defmt::error!("flash: the NVMC is already shared");
            return none;
        };
        let Some(shared) = storage::share(&*flash) else {
            defmt::error!("flash: the records' or the ghosts' region is not whole pages");
            return none;
        };
        let records = Records::new(
            WatchedFlash::new(shared.records, heartbeats),
            local(&board::RECORDS),
        );
        let ghosts = Ghosts::new(
            WatchedFlash::unwatched(shared.ghosts),
            local(&board::GHOSTS),
        );
        if records.is_none() || ghosts.is_none() {
            defmt::error!(
                "flash: records {=bool}, ghosts {=bool}: a region is not a map",
                records.is_some(),
                ghosts.is_some()
            );
        }
        Stores { records, ghosts }
    }

    /// Forgets every best time and every ghost (A+B at power-on, answered A).
    pub async fn clear(stores: &mut Stores) {
        if let Some(records) = &mut stores.records {
            match records.clear().await {
                Ok(()) => defmt::info!("records cleared"),
                Err(e) => defmt::error!("records: {=str}", e.as_str()),
            }
        }
        if let Some(ghosts) = &mut stores.ghosts {
            match ghosts.clear().await {
                Ok(()) => defmt::info!("ghosts cleared"),
                Err(e) => defmt::error!("ghosts: {=str}", e.as_str()),
            }
        }
    }

    /// The ghosts with their buffers (`None` without a store), for the game
    /// task to keep in its future where the race's never is: made there,
    /// it is written in place, never moved through a stack frame.
    pub fn kit(ghosts: Option<GhostsStore>) -> Option<Kit> {
        ghosts.map(|store| GhostKit::new(store, |_| {}))
    }
}
#[cfg(feature = "ghosts")]
pub use shared::*;

#[cfg(not(feature = "ghosts"))]
mod records_only {
    use embassy_embedded_hal::adapter::BlockingAsync;
    use embassy_nrf::nvmc::Nvmc;
    use embassy_nrf::{peripherals, Peri};
    use marble_rolling::board::microbit::{self as board, Heartbeats};
    use marble_rolling::records::Records;

    use crate::hw::WatchedFlash;

    /// The records' flash: the NVMC, blocking (the CPU waits on a page erase,
    /// about 85 ms, between levels only), each operation a heartbeat of the
    /// records task ([`WatchedFlash`]).
    pub type RecordsFlash = WatchedFlash<BlockingAsync<Nvmc<'static>>>;

    /// No ghost is kept: the game task's kit is never there.
    pub enum Kit {}

    /// No ghosts' store either.
    pub enum GhostsStore {}

    /// The best times' store; no ghosts.
    pub struct Stores {
        pub records: Option<Records<RecordsFlash>>,
        pub ghosts: Option<GhostsStore>,
    }

    /// The records over the whole NVMC (board::RECORDS).
    pub fn open(nvmc: Peri<'static, peripherals::NVMC>, heartbeats: &'static Heartbeats) -> Stores {
        let flash = WatchedFlash::new(BlockingAsync::new(Nvmc::new(nvmc)), heartbeats);
        Stores {
            records: Records::new(flash, board::RECORDS),
            ghosts: None,
        }
    }

    /// Clears the best times.
    pub async fn clear(stores: &mut Stores) {
        if let Some(records) = &mut stores.records {
            match records.clear().await {
                Ok(()) => defmt::info!("records cleared"),
                Err(e) => defmt::error!("records: {=str}", e.as_str()),
            }
        }
    }

    /// No kit without the feature.
    pub fn kit(_: Option<GhostsStore>) -> Option<Kit> {
        None
    }
}
#[cfg(not(feature = "ghosts"))]
pub use records_only::*;
