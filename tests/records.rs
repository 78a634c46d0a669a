//! Best times in flash (`marble_rolling::records`) on sequential-storage's mock
//! flash, shaped like the micro:bit v2's region (4 KiB pages, 4-byte words, the
//! 4 pages of `boards/microbit/memory.x`): a power cut at every byte of every
//! flash operation of a record update reads back the old record or the new one,
//! never garbage and never a panic; a corrupted region is recovered; and the
//! flash operations per update (the wear figure in docs/testing.md).

use embassy_futures::block_on;
use marble_rolling::records::{beats, plausible, Offer, RecordError, Records, MAX_RECORD_FRAMES};
use sequential_storage::mock_flash::{MockFlashBase, WriteCountCheck};

/// The v2's NVMC: 4 KiB pages of 1024 4-byte words; the records take 4 pages.
const PAGES: usize = 4;
type Flash = MockFlashBase<PAGES, 4, 1024>;
const REGION: core::ops::Range<u32> = 0..(PAGES as u32 * 4096);
/// The built-in levels' count: the keys the game writes.
const LEVELS: u8 = 8;

fn flash() -> Flash {
    // The NVMC writes each word once between erases.
    Flash::new(WriteCountCheck::OnceOnly, None, true)
}

fn records(flash: Flash) -> Records<Flash> {
    Records::new(flash, REGION).expect("the region is whole pages")
}

fn best(flash: &Flash, level: u8) -> Result<Option<u32>, RecordError> {
    let mut r = records(flash.clone());
    block_on(r.best(level))
}

#[test]
fn a_record_is_kept_only_when_beaten() {
    let mut r = records(flash());
    block_on(async {
        assert_eq!(r.best(3).await, Ok(None));
        assert_eq!(r.offer(3, 900).await, Ok(Offer::New { previous: None }));
        assert_eq!(r.offer(3, 950).await, Ok(Offer::Kept { best: 900 }));
        assert_eq!(
            r.offer(3, 900).await,
            Ok(Offer::Kept { best: 900 }),
            "a tie is not a record"
        );
        assert_eq!(
            r.offer(3, 899).await,
            Ok(Offer::New {
                previous: Some(900)
            })
        );
        assert_eq!(r.best(3).await, Ok(Some(899)));
        assert_eq!(r.best(4).await, Ok(None), "each level its own");
    });
    // Across a "power cycle": a new instance over the same flash.
    let f = r.into_flash();
    assert_eq!(best(&f, 3), Ok(Some(899)));
}

#[test]
fn impossible_times_are_refused() {
    let mut r = records(flash());
    block_on(async {
        assert_eq!(r.offer(0, 0).await, Err(RecordError::BadTime));
        assert_eq!(
            r.offer(0, MAX_RECORD_FRAMES + 1).await,
            Err(RecordError::BadTime)
        );
        assert_eq!(r.best(0).await, Ok(None));
    });
    assert!(plausible(1) && plausible(MAX_RECORD_FRAMES) && !plausible(0));
    assert!(beats(5, None) && beats(5, Some(6)) && !beats(6, Some(6)));
}

#[test]
fn clear_forgets_every_record() {
    let mut r = records(flash());
    block_on(async {
        for level in 0..LEVELS {
            r.offer(level, 1000 + u32::from(level)).await.unwrap();
        }
        r.clear().await.unwrap();
        for level in 0..LEVELS {
            assert_eq!(r.best(level).await, Ok(None));
        }
        // And it works again afterwards.
        assert_eq!(r.offer(2, 77).await, Ok(Offer::New { previous: None }));
    });
}

/// A flash that has seen `updates` record updates, spread over the levels and
/// each a new record (so each one writes).
fn worn(updates: u32) -> (Flash, [Option<u32>; LEVELS as usize]) {
    let mut r = records(flash());
    let mut bests = [None; LEVELS as usize];
    block_on(async {
        for n in 0..updates {
            let level = (n % u32::from(LEVELS)) as u8;
            let frames = MAX_RECORD_FRAMES - n;
            assert_eq!(
                r.offer(level, frames).await,
                Ok(Offer::New {
                    previous: bests[level as usize]
                })
            );
            bests[level as usize] = Some(frames);
        }
    });
    (r.into_flash(), bests)
}

/// Cuts the power in every erase and write of one record update, starting from
/// `before` (whose records are `bests`), and checks what reads back after each
/// cut. The cut points: every byte of the first and last 256 bytes the update
/// writes or erases (every append, every page-state marker, every migrated
/// record), and every 61st byte in between (a page erase is 4096 bytes and one
/// operation: its start, middle and end are all cut, at varying offsets).
/// Returns how many bytes the whole update wrote and erased.
fn cut_everywhere(before: &Flash, bests: &[Option<u32>; LEVELS as usize], level: u8) -> u32 {
    let old = bests[level as usize];
    let new = old.map_or(5000, |b| b - 1);
    let total = {
        let mut f = before.clone();
        f.bytes_until_shutoff = Some(u32::MAX);
        let mut r = records(f);
        block_on(r.offer(level, new)).unwrap();
        u32::MAX - r.into_flash().bytes_until_shutoff.unwrap()
    };
    let mut cut = 0u32;
    loop {
        let mut f = before.clone();
        f.bytes_until_shutoff = Some(cut);
        let mut r = records(f);
        let result = block_on(r.offer(level, new));
        let mut f = r.into_flash();
        let finished = f.bytes_until_shutoff.is_some();
        f.bytes_until_shutoff = None;
        if finished {
            assert_eq!(
                result,
                Ok(Offer::New { previous: old }),
                "no cut: it must succeed"
            );
        }
        // After the power comes back: old or new, never anything else, and the
        // other levels untouched.
        let got = best(&f, level);
        assert!(
            got == Ok(old) || got == Ok(Some(new)),
            "cut at byte {cut}: level {level} reads {got:?}, want {old:?} or {new}"
        );
        for other in (0..LEVELS).filter(|&l| l != level) {
            assert_eq!(
                best(&f, other),
                Ok(bests[other as usize]),
                "cut at byte {cut}: level {other}"
            );
        }
        // And the next update works on what the cut left.
        let mut r = records(f);
        let again = block_on(r.offer(level, new - 1));
        assert!(
            matches!(again, Ok(Offer::New { .. })),
            "cut at byte {cut}: the next update gave {again:?}"
        );
        assert_eq!(block_on(r.best(level)), Ok(Some(new - 1)));
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
fn a_power_cut_anywhere_in_an_update_leaves_the_old_record_or_the_new() {
    // A fresh region, a plain append, and every state around the page
    // boundaries, where an update migrates the live records and erases a page.
    // About 255 items fill a page (16 bytes each, less the page's state words).
    let per_page = 4096 / 16;
    let mut starts = vec![0u32, 1, 9];
    for page in 1..=(2 * PAGES as u32) {
        for back in [10u32, 9, 8, 7, 6] {
            starts.push(page * per_page - back);
        }
    }
    let mut longest = 0;
    for updates in starts {
        let (f, bests) = worn(updates);
        for level in [0u8, (updates % u32::from(LEVELS)) as u8] {
            longest = longest.max(cut_everywhere(&f, &bests, level));
        }
    }
    // The page migrations were reached: an erase is 4096 bytes.
    assert!(
        longest > 4096,
        "no update erased a page (cut at byte {longest} at most)"
    );
}

#[test]
fn a_corrupted_region_is_recovered_not_trusted() {
    let (clean, bests) = worn(40);
    // Random bytes over the live data (a deterministic generator: a test that
    // fails must fail again).
    let mut seed = 0x2545_f491_u32;
    for trial in 0..200 {
        let mut f = clean.clone();
        let bytes = f.as_bytes_mut();
        let flips = 1 + trial % 6;
        for _ in 0..flips {
            seed ^= seed << 13;
            seed ^= seed >> 17;
            seed ^= seed << 5;
            let at = (seed as usize) % (2 * 4096);
            bytes[at] ^= 1 << (seed >> 29);
        }
        let mut r = records(f);
        for level in 0..LEVELS {
            match block_on(r.best(level)) {
                // Either a value that was really stored for this level at some
                // time (the newest, or an older one a broken newer item hides:
                // `worn` stores decreasing times), or none…
                Ok(Some(v)) => {
                    let newest = bests[level as usize].unwrap();
                    assert!(
                        v >= newest
                            && (MAX_RECORD_FRAMES - v) % u32::from(LEVELS) == u32::from(level),
                        "trial {trial}: level {level} reads {v}, never stored for it"
                    );
                }
                Ok(None) => {}
                // …or the region was found corrupted and erased.
                Err(RecordError::Corrupted) => {}
                Err(e) => panic!("trial {trial}: level {level}: {e:?}"),
            }
        }
        // Whatever happened, records work afterwards.
        assert!(
            matches!(block_on(r.offer(1, 10)), Ok(Offer::New { .. })),
            "trial {trial}"
        );
        assert_eq!(block_on(r.best(1)), Ok(Some(10)), "trial {trial}");
    }
}

#[test]
fn a_region_of_garbage_is_erased_and_works_again() {
    let mut f = flash();
    let mut x = 7u32;
    for b in f.as_bytes_mut() {
        x = x.wrapping_mul(1_103_515_245).wrapping_add(12_345);
        *b = (x >> 16) as u8;
    }
    let mut r = records(f);
    let first = block_on(r.best(0));
    assert!(
        matches!(first, Ok(None) | Err(RecordError::Corrupted)),
        "{first:?}"
    );
    assert!(matches!(block_on(r.offer(0, 300)), Ok(Offer::New { .. })));
    assert_eq!(block_on(r.best(0)), Ok(Some(300)));
}

/// The wear figure in docs/testing.md: flash operations per record update, measured over
/// 20 000 updates (many times around the region), printed with
/// `cargo test --features records --test records wear -- --nocapture`.
#[test]
fn wear() {
    const UPDATES: u64 = 20_000;
    let mut r = records(flash());
    let start = r.flash().stats_snapshot();
    block_on(async {
        for n in 0..UPDATES {
            let level = (n % u64::from(LEVELS)) as u8;
            // Every update a new record (the worst case: each one writes).
            r.offer(level, MAX_RECORD_FRAMES - n as u32).await.unwrap();
        }
    });
    let used = start.compare_to(r.flash().stats_snapshot());
    let erases_per_update = used.erases as f64 / UPDATES as f64;
    let bytes_per_update = used.bytes_written as f64 / UPDATES as f64;
    // nRF52833: 10 000 erase cycles per page (product specification, NVMC);
    // the erases rotate over the region's pages.
    let updates_per_life = 10_000.0 * PAGES as f64 / erases_per_update;
    println!(
        "records wear: per update {:.2} writes, {:.1} bytes written, {:.2} reads, {:.5} page erases \
         ({} erases in {UPDATES} updates); {:.2e} updates before a page reaches 10 000 erases",
        used.writes as f64 / UPDATES as f64,
        bytes_per_update,
        used.reads as f64 / UPDATES as f64,
        erases_per_update,
        used.erases,
        updates_per_life,
    );
    // One item a record (16 bytes) plus the live records moved at each page
    // turn: well under two items' worth.
    assert!(
        bytes_per_update < 32.0,
        "{bytes_per_update} bytes per update"
    );
    // A page turn every ~250 updates at most once.
    assert!(
        erases_per_update < 1.0 / 200.0,
        "{erases_per_update} erases per update"
    );
}

/// QEMU's RAM flash keeps the NVMC's rules, and the records run on it as on the
/// mock flash: a record survives a save and reload of the image.
#[test]
fn qemu_ram_flash_holds_records_across_a_reload() {
    use embedded_storage_async::nor_flash::{
        NorFlash, NorFlashError, NorFlashErrorKind, ReadNorFlash,
    };
    use marble_rolling::board::qemu::ram_flash::RamFlash;
    const N: usize = 4 * 4096;
    let mut r = Records::new(RamFlash::<N>::new(), 0..N as u32).unwrap();
    assert_eq!(block_on(r.offer(5, 640)), Ok(Offer::New { previous: None }));
    let saved = *r.flash().image();
    let mut reloaded = RamFlash::<N>::new();
    *reloaded.image_mut() = saved;
    let mut r = Records::new(reloaded, 0..N as u32).unwrap();
    assert_eq!(block_on(r.best(5)), Ok(Some(640)));
    // NOR rules: a write only clears bits; misaligned or out-of-range is refused.
    let mut f = RamFlash::<4096>::new();
    block_on(async {
        f.write(0, &[0xF0, 0x0F, 0xFF, 0x00]).await.unwrap();
        f.write(0, &[0x3C, 0xFF, 0x00, 0xFF]).await.unwrap();
        let mut b = [0u8; 4];
        f.read(0, &mut b).await.unwrap();
        assert_eq!(b, [0x30, 0x0F, 0x00, 0x00]);
        assert_eq!(
            f.write(2, &[0; 4]).await.unwrap_err().kind(),
            NorFlashErrorKind::NotAligned
        );
        assert_eq!(
            f.write(4096, &[0; 4]).await.unwrap_err().kind(),
            NorFlashErrorKind::OutOfBounds
        );
        f.erase(0, 4096).await.unwrap();
        f.read(0, &mut b).await.unwrap();
        assert_eq!(b, [0xFF; 4]);
    });
}

/// The records' items on flash are what firmwares before `records::Slot`
/// wrote (sequential-storage's map with a one-byte key, the level, and a
/// four-byte value, the frames): a board's best times survive the update
/// that gave the records and the ghosts one key type.
#[test]
fn records_written_by_an_older_firmware_read_back() {
    use sequential_storage::cache::Cache;
    use sequential_storage::map::{MapConfig, MapStorage};
    let mut old =
        MapStorage::<u8, _, _>::new(flash(), MapConfig::new(REGION), Cache::new_uncached());
    let mut buffer = [0u8; 16];
    block_on(async {
        for level in 0..LEVELS {
            let frames = 700 + u32::from(level);
            old.store_item(&mut buffer, &level, &frames).await.unwrap();
        }
    });
    let f = old.destroy().0;
    let mut r = records(f);
    block_on(async {
        for level in 0..LEVELS {
            assert_eq!(r.best(level).await, Ok(Some(700 + u32::from(level))));
        }
        assert_eq!(
            r.offer(2, 650).await,
            Ok(Offer::New {
                previous: Some(702)
            })
        );
    });
    // And the other way: what this firmware writes, the older one reads.
    let f = r.into_flash();
    let mut old = MapStorage::<u8, _, _>::new(f, MapConfig::new(REGION), Cache::new_uncached());
    let got = block_on(old.fetch_item::<u32>(&mut buffer, &2)).unwrap();
    assert_eq!(got, Some(650));
}

/// A level's key is one byte under the ghosts' tag bit: from 128 on there
/// is no record, and offering one is an error, not a ghost's key.
#[test]
fn levels_from_128_have_no_record() {
    let mut r = records(flash());
    block_on(async {
        assert_eq!(r.offer(127, 500).await, Ok(Offer::New { previous: None }));
        assert_eq!(r.best(127).await, Ok(Some(500)));
        assert_eq!(r.offer(128, 500).await, Err(RecordError::BadLevel));
        assert_eq!(r.offer(255, 500).await, Err(RecordError::BadLevel));
        assert_eq!(r.best(128).await, Ok(None));
        assert_eq!(r.best(127).await, Ok(Some(500)));
    });
}
