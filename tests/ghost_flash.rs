//! The boards' ghosts in flash (`marble_rolling::records::Ghosts`) on
//! sequential-storage's mock flash, with the micro:bit v2's pages (4 KiB of
//! 4-byte words, each word written once between erases; 8 of them here): a
//! power cut at any byte of a ghost's write leaves the old ghost or the new
//! one, whole; a full region makes the oldest ghost of another level give way;
//! a ghost longer than a page is refused before anything is written; and
//! QEMU's RAM flash keeps a ghost across a reload of its image. Module `v2`:
//! the v2's own regions on a mock of its whole flash, shared by the records
//! and the ghosts.

use embassy_futures::block_on;
use marble_rolling::game::ghost::{Ghost, GhostError, GhostWriter};
use marble_rolling::input::axes::AccelMg;
use marble_rolling::input::sensor::Calibration;
use marble_rolling::records::{
    ghost_key, ghost_work_bytes, max_ghost_bytes, GhostStoreError, Ghosts, Kept, Slot,
};
use sequential_storage::cache::Cache;
use sequential_storage::map::{MapConfig, MapStorage};
use sequential_storage::mock_flash::{MockFlashBase, WriteCountCheck};

const PAGES: usize = 8;
type Flash = MockFlashBase<PAGES, 4, 1024>;
const REGION: core::ops::Range<u32> = 0..(PAGES as u32 * 4096);
/// The longest ghost a 4 KiB page keeps.
const MAX: usize = max_ghost_bytes::<Flash>();

fn flash() -> Flash {
    Flash::new(WriteCountCheck::OnceOnly, None, true)
}

fn ghosts(flash: Flash) -> Ghosts<Flash> {
    Ghosts::new(flash, REGION).expect("the region is whole pages")
}

/// A ghost of about `len` bytes (a few less: the writer stops whole), its
/// readings from `seed`, ending on hash `seed`.
fn ghost_of(len: usize, seed: i32) -> Vec<u8> {
    let mut buf = vec![0u8; len];
    let mut w = GhostWriter::new(&mut buf).expect("room for the header");
    let mut n = 0i32;
    loop {
        // Changes of one or two bytes per axis, never a repeat.
        let reading = AccelMg::new(seed + n % 97, 1000 - n % 13, (n * 7) % 300);
        match w.push(reading) {
            Ok(()) => n += 1,
            Err(GhostError::Full) => break,
            Err(e) => panic!("{e}"),
        }
    }
    w.finish(seed as u64, Calibration::NONE)
        .expect("the writer stopped whole")
        .to_vec()
}

fn load(flash: &Flash, name: &str) -> Result<Option<Vec<u8>>, GhostStoreError> {
    let mut g = ghosts(flash.clone());
    let mut buf = vec![0u8; ghost_work_bytes::<Flash>(MAX)];
    block_on(g.load(name, &mut buf)).map(|b| b.map(<[u8]>::to_vec))
}

/// Keeps `ghost` with a work buffer for the longest ghost (making room reads
/// the others through it).
fn keep(g: &mut Ghosts<Flash>, name: &str, ghost: &[u8]) -> Result<Kept, GhostStoreError> {
    let mut work = vec![0u8; ghost_work_bytes::<Flash>(MAX)];
    block_on(g.keep(name, ghost, &mut work))
}

#[test]
fn the_keys_are_fnv1a_of_the_name() {
    // FNV-1a's published test vectors.
    assert_eq!(ghost_key(""), 0x811c_9dc5);
    assert_eq!(ghost_key("a"), 0xe40c_292c);
    assert_eq!(ghost_key("foobar"), 0xbf9c_f968);
    assert_ne!(ghost_key("maze-11-4x4x1-d1"), ghost_key("maze-12-4x4x1-d1"));
    // A page of 4096 bytes: two state words, the item's header, the key.
    assert_eq!(MAX, 4096 - 8 - 8 - 4);
}

#[test]
fn a_ghost_is_kept_per_level_and_replaced() {
    let mut g = ghosts(flash());
    let corner = ghost_of(900, 1);
    let tour = ghost_of(3000, 2);
    assert_eq!(
        keep(&mut g, "corner", &corner).map(|k| k.bytes),
        Ok(corner.len())
    );
    assert_eq!(
        keep(&mut g, "grand-tour", &tour).map(|k| k.bytes),
        Ok(tour.len())
    );
    let f = g.into_flash();
    // Across a "power cycle": a new instance over the same flash.
    assert_eq!(load(&f, "corner"), Ok(Some(corner.clone())));
    assert_eq!(load(&f, "grand-tour"), Ok(Some(tour.clone())));
    assert_eq!(load(&f, "switchback"), Ok(None));
    let mut g = ghosts(f);
    let faster = ghost_of(700, 3);
    keep(&mut g, "corner", &faster).unwrap();
    let f = g.into_flash();
    assert_eq!(load(&f, "corner"), Ok(Some(faster)));
    assert_eq!(load(&f, "grand-tour"), Ok(Some(tour)));
    // A buffer too small for the stored ghost is an error naming the need.
    let mut g = ghosts(f);
    let mut small = [0u8; 64];
    assert!(matches!(
        block_on(g.load("grand-tour", &mut small)),
        Err(GhostStoreError::Buffer { .. })
    ));
}

/// Cuts the power in every erase and write of keeping `new` as `name`'s ghost
/// over `before`: at every byte of the first and last 256 bytes the update
/// writes or erases, and every 61st in between. After each cut `name` reads
/// back its old ghost or `new`, whole; the other levels' ghosts are
/// untouched; and the next ghost is kept. Returns the bytes the update wrote
/// and erased.
fn cut_everywhere(before: &Flash, name: &str, new: &[u8], others: &[(&str, Vec<u8>)]) -> u32 {
    let old = load(before, name).unwrap();
    let total = {
        let mut f = before.clone();
        f.bytes_until_shutoff = Some(u32::MAX);
        let mut g = ghosts(f);
        keep(&mut g, name, new).unwrap();
        u32::MAX - g.into_flash().bytes_until_shutoff.unwrap()
    };
    let next = ghost_of(500, 99);
    let mut cut = 0u32;
    loop {
        let mut f = before.clone();
        f.bytes_until_shutoff = Some(cut);
        let mut g = ghosts(f);
        let result = keep(&mut g, name, new);
        let mut f = g.into_flash();
        let finished = f.bytes_until_shutoff.is_some();
        f.bytes_until_shutoff = None;
        if finished {
            assert!(result.is_ok(), "no cut: it must succeed, got {result:?}");
        }
        let got = load(&f, name).unwrap_or_else(|e| panic!("cut at byte {cut}: {e:?}"));
        assert!(
            got == old || got.as_deref() == Some(new),
            "cut at byte {cut}: {name} reads {} bytes, neither the old ghost nor the new",
            got.map_or(0, |g| g.len())
        );
        if let Some(bytes) = &got {
            assert!(
                Ghost::parse(bytes).is_ok(),
                "cut at byte {cut}: a broken ghost"
            );
        }
        for (other, bytes) in others.iter().filter(|(o, _)| *o != name) {
            assert_eq!(
                load(&f, other),
                Ok(Some(bytes.clone())),
                "cut at byte {cut}: {other}"
            );
        }
        let mut g = ghosts(f);
        assert!(
            keep(&mut g, name, &next).is_ok(),
            "cut at byte {cut}: the next ghost is not kept"
        );
        assert_eq!(load(&g.into_flash(), name), Ok(Some(next.clone())));
        if finished {
            assert_eq!(cut, total);
            return total;
        }
        cut += if cut < 256 || cut + 256 >= total {
            1
        } else {
            61
        };
    }
}

#[test]
fn a_power_cut_while_a_ghost_is_written_leaves_the_old_or_the_new() {
    // A first ghost on an empty region, a replacement appended, and one that
    // turns pages: the region holds two large ghosts of other levels, so a
    // third page's worth migrates the live ones and erases a page.
    let a = ("corner", ghost_of(2500, 1));
    let b = ("switchback", ghost_of(3500, 2));
    let c = ("cavern", ghost_of(3800, 3));
    let f = flash();
    cut_everywhere(&f, a.0, &a.1, &[]);
    let mut g = ghosts(f);
    keep(&mut g, a.0, &a.1).unwrap();
    let f = g.into_flash();
    cut_everywhere(&f, a.0, &ghost_of(2000, 4), std::slice::from_ref(&a));
    let mut g = ghosts(f);
    keep(&mut g, b.0, &b.1).unwrap();
    keep(&mut g, c.0, &c.1).unwrap();
    for n in 0..PAGES as i32 {
        keep(&mut g, a.0, &ghost_of(3000, 10 + n)).unwrap();
    }
    let a = (a.0, ghost_of(3000, 10 + PAGES as i32 - 1));
    let f = g.into_flash();
    let longest = cut_everywhere(&f, a.0, &ghost_of(3900, 5), &[a.clone(), b, c]);
    assert!(
        longest > 4096,
        "the update erased no page (cut at byte {longest} at most)"
    );
}

#[test]
fn a_full_region_makes_the_oldest_ghost_give_way() {
    // Each ghost takes most of a page: the region keeps one less than its
    // pages (the crate keeps a page free to migrate into).
    let mut g = ghosts(flash());
    let names: Vec<String> = (0..PAGES + 3)
        .map(|n| format!("maze-{n}-4x4x1-d1"))
        .collect();
    let mut kept: Vec<(String, Vec<u8>)> = Vec::new();
    let mut evicted_total = 0;
    for (n, name) in names.iter().enumerate() {
        let ghost = ghost_of(3000, n as i32);
        let k = keep(&mut g, name, &ghost).unwrap_or_else(|e| panic!("{name}: {e:?}"));
        evicted_total += usize::from(k.evicted);
        kept.push((name.clone(), ghost));
    }
    assert!(
        evicted_total >= 3,
        "the region never filled ({evicted_total} evicted)"
    );
    let f = g.into_flash();
    // Every ghost left is whole, as many gave way as were evicted (the one
    // sitting oldest in the region: migrations move live ghosts forward),
    // and the last ghost kept is there.
    let mut gone = 0;
    for (name, ghost) in &kept {
        match load(&f, name).unwrap() {
            Some(bytes) => assert_eq!(&bytes, ghost, "{name}"),
            None => gone += 1,
        }
    }
    assert_eq!(gone, evicted_total);
    assert!(load(&f, names.last().unwrap()).unwrap().is_some());
}

#[test]
fn a_region_too_small_for_two_ghosts_says_full() {
    // Two pages: one live page, one to migrate into; a ghost per level of
    // most of a page each. The second level's ghost finds the first one's
    // in the way, evicts it, and is kept.
    type Small = MockFlashBase<2, 4, 1024>;
    let mut g = Ghosts::new(Small::new(WriteCountCheck::OnceOnly, None, true), 0..8192).unwrap();
    let mut work = vec![0u8; ghost_work_bytes::<Small>(MAX)];
    let a = ghost_of(3000, 1);
    let b = ghost_of(3000, 2);
    block_on(async {
        assert!(g.keep("a", &a, &mut work).await.is_ok());
        let k = g.keep("b", &b, &mut work).await;
        assert_eq!(k.map(|k| k.evicted), Ok(1), "a gives way to b");
        let mut buf = vec![0u8; work.len()];
        assert_eq!(g.load("a", &mut buf).await, Ok(None));
        assert_eq!(
            g.load("b", &mut buf).await.map(|b| b.map(<[u8]>::to_vec)),
            Ok(Some(b.clone()))
        );
        // A ghost the size of a whole page cannot share a page with the
        // eviction marks: not kept, said so, and the region works on.
        let c = ghost_of(MAX, 3);
        assert_eq!(g.keep("c", &c, &mut work).await, Err(GhostStoreError::Full));
        assert_eq!(g.load("c", &mut buf).await, Ok(None));
        let d = ghost_of(1000, 4);
        assert!(g.keep("d", &d, &mut work).await.is_ok());
        assert_eq!(
            g.load("d", &mut buf).await.map(|b| b.map(<[u8]>::to_vec)),
            Ok(Some(d))
        );
    });
}

#[test]
fn a_ghost_longer_than_a_page_is_refused_and_nothing_is_written() {
    let mut g = ghosts(flash());
    let short = ghost_of(1000, 1);
    keep(&mut g, "corner", &short).unwrap();
    let before = g.flash().as_bytes().to_vec();
    let long = ghost_of(MAX + 64, 2);
    assert!(long.len() > MAX);
    assert_eq!(
        keep(&mut g, "corner", &long),
        Err(GhostStoreError::TooLong {
            len: long.len(),
            max: MAX
        })
    );
    assert_eq!(
        GhostStoreError::TooLong { len: 1, max: 0 }.as_str(),
        "ghost longer than a flash page: not kept"
    );
    assert_eq!(g.flash().as_bytes(), &before[..], "nothing written");
    // The longest that fits is kept.
    let longest = ghost_of(MAX, 3);
    assert!(longest.len() <= MAX && longest.len() + 8 > MAX);
    keep(&mut g, "corner", &longest).unwrap();
    assert_eq!(load(&g.into_flash(), "corner"), Ok(Some(longest)));
}

#[test]
fn a_stored_item_that_is_not_a_ghost_is_no_ghost() {
    let mut g = ghosts(flash());
    let mut ghost = ghost_of(800, 1);
    // Well-formed for the flash (its CRCs hold), but one frame short.
    ghost[4] = ghost[4].wrapping_add(1);
    keep(&mut g, "corner", &ghost).unwrap();
    assert_eq!(load(&g.into_flash(), "corner"), Ok(None));
}

/// On flash a ghost's key is its name's FNV-1a hash with the tag bit set in
/// its first byte (little-endian), which a record's key (a level below 128)
/// never has: the two stores share one key type (`records::Slot`).
#[test]
fn a_ghosts_key_on_flash_is_tagged() {
    assert_eq!(Slot::ghost("a"), Slot::ghost("a"));
    assert_ne!(Slot::ghost("a"), Slot::ghost("foobar"));
    assert!(Slot::ghost("a").is_ghost() && !Slot::level(3).unwrap().is_ghost());
    assert_eq!(Slot::level(128), None);
    let mut g = ghosts(flash());
    let ghost = ghost_of(300, 4);
    keep(&mut g, "a", &ghost).unwrap();
    let f = g.into_flash();
    // The raw map reads the item back under the tagged hash: 0xe40c_292c
    // with 0x80 in its low byte.
    let mut old = MapStorage::<u32, _, _>::new(f, MapConfig::new(REGION), Cache::new_uncached());
    let mut buf = vec![0u8; ghost_work_bytes::<Flash>(MAX)];
    let got = block_on(old.fetch_item::<&[u8]>(&mut buf, &0xe40c_29ac)).unwrap();
    assert_eq!(got, Some(&ghost[..]));
}

/// Ghosts an older firmware kept under the bare hash (no tag bit) read back
/// as records' keys: the first load after a power-up finds them, erases the
/// region and says so once; the region then works as new. A ghost whose
/// bare hash already had the bit is the same key as before.
#[test]
fn ghosts_of_an_older_firmware_are_cleared_once_and_said() {
    let old_ghost = ghost_of(500, 2);
    let mut old =
        MapStorage::<u32, _, _>::new(flash(), MapConfig::new(REGION), Cache::new_uncached());
    let mut work = vec![0u8; ghost_work_bytes::<Flash>(MAX)];
    // "a": 0xe40c_292c, the tag bit clear.
    block_on(old.store_item(&mut work, &ghost_key("a"), &&old_ghost[..])).unwrap();
    let f = old.destroy().0;
    let mut g = ghosts(f.clone());
    let mut buf = vec![0u8; ghost_work_bytes::<Flash>(MAX)];
    assert_eq!(
        block_on(g.load("corner", &mut buf)),
        Err(GhostStoreError::OlderFormat)
    );
    assert_eq!(
        GhostStoreError::OlderFormat.as_str(),
        "ghosts of an older firmware: region cleared"
    );
    assert_eq!(block_on(g.load("a", &mut buf)), Ok(None));
    let new = ghost_of(600, 3);
    keep(&mut g, "a", &new).unwrap();
    assert_eq!(load(&g.into_flash(), "a"), Ok(Some(new.clone())));
    // A keep first clears the region too, and keeps its ghost.
    let mut g = ghosts(f);
    keep(&mut g, "b", &new).unwrap();
    let f = g.into_flash();
    assert_eq!(load(&f, "b"), Ok(Some(new.clone())));
    assert_eq!(load(&f, "a"), Ok(None));
    // "": 0x811c_9dc5, the tag bit set: an older firmware's ghost of that
    // name is this firmware's, and nothing is cleared.
    let mut old =
        MapStorage::<u32, _, _>::new(flash(), MapConfig::new(REGION), Cache::new_uncached());
    block_on(old.store_item(&mut work, &ghost_key(""), &&old_ghost[..])).unwrap();
    assert_eq!(load(&old.destroy().0, ""), Ok(Some(old_ghost)));
}

/// QEMU's RAM flash (the NVMC's rules) keeps a ghost across a save and reload
/// of its image.
#[test]
fn qemu_ram_flash_holds_a_ghost_across_a_reload() {
    use marble_rolling::board::qemu::ram_flash::RamFlash;
    const N: usize = 8 * 4096;
    let mut g = Ghosts::new(RamFlash::<N>::new(), 0..N as u32).unwrap();
    let ghost = ghost_of(2000, 7);
    let mut work = vec![0u8; ghost_work_bytes::<RamFlash<N>>(ghost.len())];
    block_on(g.keep("corner", &ghost, &mut work)).unwrap();
    let saved = g.flash().image().to_vec();
    let mut reloaded = RamFlash::<N>::new();
    reloaded.image_mut().copy_from_slice(&saved);
    let mut g = Ghosts::new(reloaded, 0..N as u32).unwrap();
    let mut buf = vec![0u8; ghost_work_bytes::<RamFlash<N>>(MAX)];
    assert_eq!(block_on(g.load("corner", &mut buf)), Ok(Some(&ghost[..])));
}

/// The micro:bit v2's one NVMC shared by the records task and the game
/// task's ghosts (`board::microbit::storage`), on a mock of its whole
/// 512 KiB flash with the board's own regions. The v2 runs nowhere here:
/// these tests are what shows the sharing works.
#[cfg(feature = "shared-flash")]
mod v2 {
    use super::ghost_of;
    use embassy_futures::{block_on, join::join, yield_now};
    use embedded_storage::nor_flash as blocking;
    use embedded_storage_async::nor_flash::{ErrorType, NorFlash, ReadNorFlash};
    use marble_rolling::app::GhostKit;
    use marble_rolling::board::levels_region;
    use marble_rolling::board::microbit::storage::{
        fits, local, nvmc_busy_us, overlap, partition, share, Region, RegionError, Shared,
        LONGEST_STALL_MS,
    };
    use marble_rolling::board::microbit::{GHOSTS, GHOST_BYTES, RECORDS};
    use marble_rolling::records::{ghost_work_bytes, Ghosts, Offer, Records};
    use sequential_storage::mock_flash::{MockFlashBase, WriteCountCheck};
    use std::cell::{Cell, RefCell};

    /// The nRF52833's flash: 128 pages of 4 KiB, 4-byte words.
    type Nvmc = MockFlashBase<128, 4, 1024>;

    /// The mock, blocking as the NVMC is (its operations end within the
    /// call), each erase and write logged by its address and its NVMC time
    /// (the datasheet's maxima) added up until someone takes it.
    struct Logged<'c> {
        flash: Nvmc,
        log: Vec<u32>,
        busy_us: &'c Cell<u64>,
    }

    impl blocking::ErrorType for Logged<'_> {
        type Error = <Nvmc as ErrorType>::Error;
    }

    impl blocking::ReadNorFlash for Logged<'_> {
        const READ_SIZE: usize = Nvmc::READ_SIZE;
        fn read(&mut self, offset: u32, bytes: &mut [u8]) -> Result<(), Self::Error> {
            block_on(self.flash.read(offset, bytes))
        }
        fn capacity(&self) -> usize {
            self.flash.capacity()
        }
    }

    impl blocking::NorFlash for Logged<'_> {
        const WRITE_SIZE: usize = Nvmc::WRITE_SIZE;
        const ERASE_SIZE: usize = Nvmc::ERASE_SIZE;
        fn erase(&mut self, from: u32, to: u32) -> Result<(), Self::Error> {
            self.log.push(from);
            let pages = u64::from((to - from) / Nvmc::ERASE_SIZE as u32);
            self.busy_us
                .set(self.busy_us.get() + nvmc_busy_us(pages, 0));
            block_on(self.flash.erase(from, to))
        }
        fn write(&mut self, offset: u32, bytes: &[u8]) -> Result<(), Self::Error> {
            self.log.push(offset);
            let us = nvmc_busy_us(0, bytes.len() as u64);
            self.busy_us.set(self.busy_us.get() + us);
            block_on(self.flash.write(offset, bytes))
        }
    }

    /// A mock flash of other pages, blocking, for the regions' checks.
    struct Blocking<F>(F);

    impl<F: ErrorType> blocking::ErrorType for Blocking<F> {
        type Error = F::Error;
    }

    impl<F: ReadNorFlash> blocking::ReadNorFlash for Blocking<F> {
        const READ_SIZE: usize = F::READ_SIZE;
        fn read(&mut self, offset: u32, bytes: &mut [u8]) -> Result<(), Self::Error> {
            block_on(self.0.read(offset, bytes))
        }
        fn capacity(&self) -> usize {
            self.0.capacity()
        }
    }

    impl<F: NorFlash> blocking::NorFlash for Blocking<F> {
        const WRITE_SIZE: usize = F::WRITE_SIZE;
        const ERASE_SIZE: usize = F::ERASE_SIZE;
        fn erase(&mut self, from: u32, to: u32) -> Result<(), Self::Error> {
            block_on(self.0.erase(from, to))
        }
        fn write(&mut self, offset: u32, bytes: &[u8]) -> Result<(), Self::Error> {
            block_on(self.0.write(offset, bytes))
        }
    }

    fn logged(flash: Nvmc, busy_us: &Cell<u64>) -> RefCell<Logged<'_>> {
        RefCell::new(Logged {
            flash,
            log: Vec::new(),
            busy_us,
        })
    }

    fn erased() -> Nvmc {
        Nvmc::new(WriteCountCheck::OnceOnly, None, true)
    }

    type Part<'a, 'c> = Region<'a, Logged<'c>>;

    fn stores<'a, 'c>(
        flash: &'a RefCell<Logged<'c>>,
    ) -> (Records<Part<'a, 'c>>, Ghosts<Part<'a, 'c>>) {
        let Shared { records, ghosts } = share(flash).expect("the v2's regions on its flash");
        (
            Records::new(records, local(&RECORDS)).unwrap(),
            Ghosts::new(ghosts, local(&GHOSTS)).unwrap(),
        )
    }

    /// The bytes outside the two stores' regions are as erased as they
    /// started (the levels region between them above all).
    fn outside_untouched(flash: &Nvmc) {
        for (at, &b) in flash.as_bytes().iter().enumerate() {
            let at = at as u32;
            if !RECORDS.contains(&at) && !GHOSTS.contains(&at) {
                assert_eq!(b, 0xFF, "byte {at:#x} written, outside both stores");
            }
        }
    }

    #[test]
    fn the_regions_are_whole_pages_and_apart() {
        assert!(fits::<Nvmc>(&RECORDS) && fits::<Nvmc>(&GHOSTS));
        assert!(!overlap(&RECORDS, &GHOSTS));
        assert!(!overlap(&GHOSTS, &levels_region::V2));
        assert!(!overlap(&RECORDS, &levels_region::V2));
        assert!(overlap(&(0..4096), &(4095..8192)) && !overlap(&(0..4096), &(4096..8192)));
        assert_eq!(local(&GHOSTS), 0..16 * 1024);
        // Not whole pages, empty or past the flash's end: no region (never
        // a panic).
        let busy = Cell::new(0);
        let flash = logged(erased(), &busy);
        assert!(partition(&flash, 0x7_7000..0x7_7800).is_none());
        assert!(partition(&flash, 0x7_7800..0x7_8800).is_none());
        assert!(partition(&flash, 0x7_7000..0x7_7000).is_none());
        assert!(partition(&flash, 0x7_F000..0x8_1000).is_none());
        let parts = share(&flash).expect("the v2's regions on its flash");
        assert_eq!(parts.ghosts.offset(), GHOSTS.start);
        assert_eq!(parts.records.size(), RECORDS.end - RECORDS.start);
        // Each region's operations stop at its end, as offsets from its
        // start; a flash already borrowed is an error, never a panic.
        let Shared {
            mut records,
            mut ghosts,
        } = parts;
        let size = records.size();
        let past = block_on(records.write(size - 4, &[0; 8]));
        assert!(matches!(past, Err(RegionError::OutOfBounds)), "{past:?}");
        let wrap = block_on(records.erase(8192, 4096));
        assert!(matches!(wrap, Err(RegionError::OutOfBounds)), "{wrap:?}");
        block_on(ghosts.write(0, &[1, 2, 3, 4])).unwrap();
        assert_eq!(flash.borrow().flash.as_bytes()[GHOSTS.start as usize], 1);
        let held = flash.borrow_mut();
        let mut word = [0u8; 4];
        let busy_read = block_on(ghosts.read(0, &mut word));
        assert!(matches!(busy_read, Err(RegionError::Busy)), "{busy_read:?}");
        drop(held);
        block_on(ghosts.read(0, &mut word)).unwrap();
        assert_eq!(word, [1, 2, 3, 4]);
        // On a flash of 8 KiB pages the ghosts' region (0x77000) is not
        // page-aligned: no stores, said by `None`.
        type Big = MockFlashBase<64, 4, 2048>;
        let big = RefCell::new(Blocking(Big::new(WriteCountCheck::OnceOnly, None, true)));
        assert!(share(&big).is_none());
    }

    #[test]
    fn records_and_ghosts_written_at_once_each_keep_their_own() {
        let busy = Cell::new(0);
        let flash = logged(erased(), &busy);
        let (mut records, mut ghosts) = stores(&flash);
        let kept: Vec<(String, Vec<u8>)> = (0..6)
            .map(|n| (format!("level-{n}"), ghost_of(1500 + 80 * n, n as i32)))
            .collect();
        let records_task = async {
            for round in 0..3u32 {
                for level in 0..10u8 {
                    let offer = records
                        .offer(level, 1000 - round * 100 - u32::from(level))
                        .await
                        .unwrap();
                    assert!(matches!(offer, Offer::New { .. }), "{level}: {offer:?}");
                }
            }
        };
        let game_task = async {
            let mut work = vec![0u8; ghost_work_bytes::<Nvmc>(GHOST_BYTES)];
            for (name, ghost) in kept.iter().chain(kept.iter()) {
                ghosts.keep(name, ghost, &mut work).await.unwrap();
            }
        };
        block_on(join(records_task, game_task));
        block_on(async {
            for level in 0..10u8 {
                assert_eq!(records.best(level).await, Ok(Some(800 - u32::from(level))));
            }
            let mut buf = vec![0u8; ghost_work_bytes::<Nvmc>(GHOST_BYTES)];
            // The last ghosts kept are there, whole (older ones gave way).
            for (name, ghost) in &kept[4..] {
                let got = ghosts.load(name, &mut buf).await.unwrap();
                assert_eq!(got, Some(&ghost[..]), "{name}");
            }
        });
        let nvmc = flash.into_inner();
        // The two tasks' operations did interleave, one at a time.
        let turns = nvmc
            .log
            .windows(2)
            .filter(|w| RECORDS.contains(&w[0]) != RECORDS.contains(&w[1]))
            .count();
        assert!(turns > 20, "the stores took {turns} turns");
        outside_untouched(&nvmc.flash);
    }

    #[test]
    fn a_power_cut_in_a_ghost_write_leaves_every_best_time() {
        let busy = Cell::new(0);
        let flash = logged(erased(), &busy);
        let (mut records, mut ghosts) = stores(&flash);
        let mut work = vec![0u8; ghost_work_bytes::<Nvmc>(GHOST_BYTES)];
        block_on(async {
            for level in 0..10u8 {
                records.offer(level, 500 + u32::from(level)).await.unwrap();
            }
            // Ghosts that fill most of the region: the next one turns a page
            // (migrates and erases).
            for n in 0..6 {
                let g = ghost_of(GHOST_BYTES - 100, n);
                ghosts
                    .keep(&format!("maze-{n}"), &g, &mut work)
                    .await
                    .unwrap();
            }
        });
        let before = flash.into_inner().flash;
        let new = ghost_of(GHOST_BYTES - 60, 9);
        let mut cut = 0u32;
        loop {
            let mut nvmc = before.clone();
            nvmc.bytes_until_shutoff = Some(cut);
            let flash = logged(nvmc, &busy);
            let (mut records, mut ghosts) = stores(&flash);
            let result = block_on(ghosts.keep("maze-0", &new, &mut work));
            let finished = {
                let mut f = flash.try_borrow_mut().expect("no operation under way");
                let finished = f.flash.bytes_until_shutoff.is_some();
                f.flash.bytes_until_shutoff = None;
                finished
            };
            for level in 0..10u8 {
                assert_eq!(
                    block_on(records.best(level)),
                    Ok(Some(500 + u32::from(level))),
                    "cut at byte {cut}: level {level}"
                );
            }
            let mut buf = vec![0u8; ghost_work_bytes::<Nvmc>(GHOST_BYTES)];
            let got = block_on(ghosts.load("maze-0", &mut buf)).map(|g| g.map(<[u8]>::to_vec));
            if finished {
                assert!(result.is_ok(), "{result:?}");
                assert_eq!(got, Ok(Some(new.clone())));
                outside_untouched(&flash.into_inner().flash);
                assert!(cut > 4096, "the write turned no page ({cut} bytes)");
                break;
            }
            cut += if cut < 256 { 1 } else { 61 };
        }
    }

    #[test]
    fn a_ghost_write_never_holds_the_cpu_as_long_as_the_watchdog_allows() {
        // A ghost is kept in the game task, on the same thread executor as
        // the watchdog task: between two of its yields the NVMC's time must
        // stay under the watchdog's margin. Ghosts of every length the kit
        // keeps, for more levels than the region holds, so that pages turn
        // and ghosts are evicted; a sibling task notes the NVMC time since it
        // last ran.
        let longest = GhostKit::<Part<'static, 'static>, { GHOST_BYTES }>::longest();
        let busy = Cell::new(0);
        let flash = logged(erased(), &busy);
        let (_, mut ghosts) = stores(&flash);
        let mut work = vec![0u8; ghost_work_bytes::<Nvmc>(GHOST_BYTES)];
        let done = Cell::new(false);
        let (mut worst_keep, mut evicted) = (0u64, 0u32);
        let game_task = async {
            for n in 0..60usize {
                let len = 200 + (n * 733) % (longest - 200);
                let ghost = ghost_of(len, n as i32);
                let before = flash.borrow().flash.stats_snapshot();
                let kept = ghosts
                    .keep(&format!("maze-{}", n % 9), &ghost, &mut work)
                    .await
                    .unwrap();
                let used = before.compare_to(flash.borrow().flash.stats_snapshot());
                worst_keep = worst_keep.max(nvmc_busy_us(used.erases, used.bytes_written));
                evicted += u32::from(kept.evicted);
            }
            done.set(true);
        };
        let watchdog_task = async {
            let mut worst = 0u64;
            while !done.get() {
                worst = worst.max(busy.replace(0));
                yield_now().await;
            }
            worst.max(busy.get())
        };
        let ((), worst_stall) = block_on(join(game_task, watchdog_task));
        println!(
            "ghost writes on the v2: at most {worst_keep} us of NVMC a write, \
             {worst_stall} us between two yields; {evicted} evicted"
        );
        assert!(evicted > 0, "the region never filled");
        assert!(
            worst_keep > LONGEST_STALL_MS * 1000,
            "no write long enough to need the pacing ({worst_keep} us)"
        );
        assert!(
            worst_stall < LONGEST_STALL_MS * 1000,
            "{worst_stall} us between two yields, over {LONGEST_STALL_MS} ms"
        );
    }

    #[test]
    fn the_nvmc_time_counts_erases_and_words() {
        assert_eq!(nvmc_busy_us(0, 0), 0);
        assert_eq!(nvmc_busy_us(1, 0), 85_000);
        assert_eq!(nvmc_busy_us(0, 4), 41);
        assert_eq!(nvmc_busy_us(0, 5), 82);
        assert_eq!(nvmc_busy_us(2, 4096), 170_000 + 1024 * 41);
        assert_eq!(LONGEST_STALL_MS, 800);
    }
}
