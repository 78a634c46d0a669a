//! `cargo xtask hex [--check]`: the files a micro:bit owner drags onto the
//! MICROBIT drive, in `target/hex/`: `marble-rolling.hex`, the universal hex
//! (both boards' images; the board's interface chip flashes its own), and
//! `marble-rolling-v1.hex` / `marble-rolling-v2.hex`, plain Intel HEX (a V1
//! whose interface firmware predates universal hexes takes only its own).
//! The firmware is built as `cargo microbit` and `cargo microbit-v1` build
//! it (release); the formats are [`crate::hex`]'s.
//!
//! `--check` is the proof CI runs, by tools other than ours: the micro:bit
//! Foundation's library (`@microbit/microbit-universal-hex` from npm, pinned,
//! installed under `target/hex-check/`) splits the universal hex into one
//! Intel HEX per board; llvm-objcopy (rustup's llvm-tools) turns each of them,
//! each plain file and each ELF into a flat binary, and the ones of a board
//! must be equal byte for byte; and the V1 image the library took out of the
//! universal hex boots in QEMU's `microbit` machine, put in flash by QEMU's
//! loader from that .hex (not from the ELF, which only decodes the log), and
//! wins the demo.
//!
//! `--level FILE…` also writes the levels region
//! (`marble_rolling::board::levels_region`: the format, its address on each
//! board) into both images, after checking each level as `cargo sim --
//! --check` does (`FILE:line:column: message`); `--check` then wants the
//! region, read back by the firmware's own reader from each image the
//! library split off, to hold the files' levels, and the rest of each image
//! equal to the ELF's; and the V1's demo in QEMU to play the region's levels
//! first (the firmware reads its region at boot), each won with the steps and
//! `state_hash` of `cargo sim -- --level FILE --autopilot`
//! ([`crate::hex_check::region_first`]). The proof is [`crate::hex_check`].

use std::path::{Path, PathBuf};

use crate::boards::{self, Firmware, MICROBIT, MICROBIT_V1};
use crate::error::{say, Failure};
use crate::hex::{self, Image};
use crate::workspace;

use marble_rolling::board::levels_region::{self, LevelCheck};
use marble_rolling::physics::geometry::grid::{words_for, MAX_LAYERS, MAX_TILES_XZ};

/// The Foundation's library and the version CI checks against (pinned: its
/// reading of the format is the reference, and must not move under us).
pub const LIBRARY: &str = "@microbit/microbit-universal-hex";
pub const LIBRARY_VERSION: &str = "0.2.2";

/// The universal hex, in `target/hex/`.
pub const UNIVERSAL: &str = "marble-rolling.hex";

/// One board's firmware and files ([`boards::HexSection`]).
pub(crate) struct Board {
    /// `v1`, `v2`: in file names and messages.
    pub(crate) name: &'static str,
    firmware: &'static Firmware,
    /// Its block type in the universal hex.
    pub(crate) block: u16,
    /// Where its levels region is.
    pub(crate) region: u32,
}

/// A board's section; one without is this table's mistake, caught when
/// xtask compiles.
const fn section(board: &'static boards::Board) -> Board {
    match &board.hex {
        Some(hex) => Board {
            name: hex.name,
            firmware: &board.game,
            block: hex.block,
            region: hex.region,
        },
        None => panic!("a board in the universal hex needs a HexSection"),
    }
}

/// The two boards, V1 first (the order of their sections in the universal
/// hex), built as `cargo microbit-v1` and `cargo microbit` build them.
pub(crate) const BOARDS: [Board; 2] = [section(&MICROBIT_V1), section(&MICROBIT)];

impl Board {
    fn plain_file(&self) -> String {
        format!("marble-rolling-{}.hex", self.name)
    }
}

/// A board's build: its ELF and the plain file written from it.
pub(crate) struct Built {
    pub(crate) elf: PathBuf,
    /// The ELF's image alone.
    pub(crate) elf_image: Image,
    /// What the files hold: the ELF's image and the levels region, if any.
    pub(crate) image: Image,
    pub(crate) plain: PathBuf,
}

/// What [`run`] wrote: the proof's input ([`crate::hex_check::check`]).
pub(crate) struct Written {
    /// The target directory.
    pub(crate) target: PathBuf,
    /// The boards' builds, in [`BOARDS`]' order.
    pub(crate) built: Vec<Built>,
    /// The universal hex.
    pub(crate) universal: PathBuf,
    /// The level files put in the levels region (name, contents), if any.
    pub(crate) levels: Option<Vec<(String, Vec<u8>)>>,
}

/// `cargo xtask hex [--level FILE…]`: builds both firmwares and writes the
/// files (`--check` is [`crate::hex_check`]'s, on what this wrote).
pub fn run(levels: &[PathBuf]) -> Result<Written, Failure> {
    let region = if levels.is_empty() {
        None
    } else {
        let mut files = Vec::new();
        for path in levels {
            let bytes = std::fs::read(path)
                .map_err(|e| Failure::new(format!("{}: cannot read: {e}", path.display())))?;
            files.push((path.display().to_string(), bytes));
        }
        let region = region_of(&files).map_err(|e| Failure::new(e).status(2))?;
        say!(
            "levels region: {} level(s) in {} B of {} at {:#x} (v1) and {:#x} (v2)",
            files.len(),
            region.len(),
            levels_region::SIZE,
            levels_region::V1.start,
            levels_region::V2.start
        );
        Some((files, region))
    };
    let target = workspace::target_dir()?;
    let out = target.join("hex");
    std::fs::create_dir_all(&out)
        .map_err(|e| Failure::new(format!("cannot create {}: {e}", out.display())))?;
    let mut built = Vec::new();
    for board in &BOARDS {
        let elf = board.firmware.build()?;
        let mut image = image_of(&elf)?;
        if image.is_empty() {
            return Err(Failure::new(format!(
                "{}: no allocated section with contents: nothing to flash",
                elf.display()
            )));
        }
        let elf_image = image.clone();
        if let Some((_, bytes)) = &region {
            image.add(board.region, bytes).map_err(|e| {
                Failure::new(format!(
                    "{}: the {} levels region at {:#x}: {e} (the firmware reaches into it)",
                    elf.display(),
                    board.name,
                    board.region
                ))
            })?;
        }
        let plain = out.join(board.plain_file());
        let text =
            hex::intel_hex(&image).map_err(|e| Failure::new(format!("{}: {e}", elf.display())))?;
        write(&plain, &text)?;
        let (base, flat) = image.flat();
        say!(
            "{}: {} B of flash from {base:#x} to {:#x}, {} B of Intel HEX in {}",
            board.name,
            image.len(),
            u64::from(base) + flat.len() as u64,
            text.len(),
            plain.display()
        );
        built.push(Built {
            elf,
            elf_image,
            image,
            plain,
        });
    }
    let universal = out.join(UNIVERSAL);
    let text = hex::universal_hex(&built[0].image, &built[1].image);
    write(&universal, &text)?;
    say!(
        "universal hex (V1 and V2): {} B in {}",
        text.len(),
        universal.display()
    );
    Ok(Written {
        target,
        built,
        universal,
        levels: region.map(|(files, _)| files),
    })
}

/// The occupancy words of the largest level the format allows: the files
/// are checked as `cargo sim -- --check` checks them, whatever a board holds.
pub(crate) const FORMAT_WORDS: usize = words_for(MAX_TILES_XZ, MAX_LAYERS, MAX_TILES_XZ);

/// The levels region's bytes for `files` (name, contents), each level
/// checked first: `FILE:line:column: message` for the first bad one.
pub fn region_of(files: &[(String, Vec<u8>)]) -> Result<Vec<u8>, String> {
    for (name, bytes) in files {
        // Boxed: the largest level's grid is 16 KiB.
        let checked = Box::new(levels_region::level::<FORMAT_WORDS>(bytes));
        match *checked {
            Ok(_) => {}
            Err(LevelCheck::Parse(e)) => return Err(format!("{name}:{e}")),
            Err(LevelCheck::TooLarge { needs, room }) => {
                return Err(format!(
                    "{name}: needs {needs} occupancy words, the format allows {room}"
                ))
            }
        }
    }
    let texts: Vec<&[u8]> = files.iter().map(|(_, bytes)| bytes.as_slice()).collect();
    let mut region = vec![0xFF; levels_region::SIZE];
    let used = levels_region::write(&texts, &mut region).map_err(|e| match e {
        levels_region::WriteError::Count(n) => format!(
            "{n} levels: the region holds 1 to {}",
            levels_region::MAX_LEVELS
        ),
        levels_region::WriteError::TooLong { index } => {
            format!("{}: longer than 65 535 bytes", files[index].0)
        }
        levels_region::WriteError::TooBig { needs, room } => format!(
            "the levels need {needs} B of region, there are {room} B (header and 2 B per level included)"
        ),
    })?;
    region.truncate(used);
    Ok(region)
}

/// Whether the levels region of `image` (a board's, its region at `at`)
/// holds exactly `files`, read with the firmware's reader.
pub fn region_holds(image: &Image, at: u32, files: &[(String, Vec<u8>)]) -> Result<(), String> {
    let (base, flat) = image.flat();
    let start = at
        .checked_sub(base)
        .map(|offset| offset as usize)
        .filter(|&offset| offset <= flat.len())
        .ok_or_else(|| format!("the image holds nothing at {at:#x}"))?;
    let end = (start + levels_region::SIZE).min(flat.len());
    let region = levels_region::read(&flat[start..end])
        .map_err(|e| format!("the region at {at:#x} is refused: {e:?}"))?;
    if region.len() != files.len() {
        return Err(format!(
            "the region at {at:#x} holds {} levels, not {}",
            region.len(),
            files.len()
        ));
    }
    for (index, (name, bytes)) in files.iter().enumerate() {
        if region.bytes(index) != Some(bytes.as_slice()) {
            return Err(format!(
                "level {} in the region at {at:#x} is not {name}",
                index + 1
            ));
        }
    }
    Ok(())
}

fn image_of(elf: &Path) -> Result<Image, Failure> {
    let data = std::fs::read(elf)
        .map_err(|e| Failure::new(format!("cannot read {}: {e}", elf.display())))?;
    hex::image_of_elf(&data).map_err(|e| Failure::new(format!("{}: {e}", elf.display())))
}

pub(crate) fn write(path: &Path, text: &str) -> Result<(), Failure> {
    std::fs::write(path, text)
        .map_err(|e| Failure::new(format!("cannot write {}: {e}", path.display())))
}

#[cfg(test)]
mod tests {
    use super::*;

    const CORNER: &str =
        "name: my-corner\n---\n#########\n#S......#\n#######.#\n#G......#\n#########\n";

    fn files(levels: &[(&str, &str)]) -> Vec<(String, Vec<u8>)> {
        levels
            .iter()
            .map(|(name, text)| (name.to_string(), text.as_bytes().to_vec()))
            .collect()
    }

    #[test]
    fn the_region_of_level_files() {
        let good = files(&[("a.level", CORNER), ("b.level", CORNER)]);
        let region = region_of(&good).unwrap();
        assert_eq!(region.len(), levels_region::HEADER + 2 * (2 + CORNER.len()));
        let read = levels_region::read(&region).unwrap();
        assert_eq!(read.bytes(1), Some(CORNER.as_bytes()));
        // A bad level is named with its line and column, as sim --check says.
        let bad = files(&[
            ("a.level", CORNER),
            ("b.level", &CORNER.replace("#G", "#x")),
        ]);
        assert_eq!(
            region_of(&bad).unwrap_err(),
            "b.level:6:2: unknown tile (use # . O S G)"
        );
        let nine = files(&[("a.level", CORNER); 9]);
        assert!(region_of(&nine).unwrap_err().starts_with("9 levels"));
    }

    #[test]
    fn a_patched_image_holds_the_region_and_the_plain_hex_too() {
        let good = files(&[("a.level", CORNER)]);
        let region = region_of(&good).unwrap();
        let mut image = Image::default();
        image.add(0, &[1, 2, 3, 4]).unwrap();
        image.add(levels_region::V1.start, &region).unwrap();
        let back = hex::image_of_intel_hex(&hex::intel_hex(&image).unwrap()).unwrap();
        assert_eq!(region_holds(&back, levels_region::V1.start, &good), Ok(()));
        let other = files(&[("b.level", &CORNER.replace("my-corner", "other"))]);
        assert!(region_holds(&back, levels_region::V1.start, &other)
            .unwrap_err()
            .contains("is not b.level"));
        // Without the region there is nothing to read.
        let mut plain = Image::default();
        plain.add(0, &[1, 2, 3, 4]).unwrap();
        assert!(region_holds(&plain, levels_region::V1.start, &good).is_err());
        // Code in the region's place: the patch is refused.
        let mut big = Image::default();
        big.add(levels_region::V1.start - 2, &[0; 4]).unwrap();
        assert!(big.add(levels_region::V1.start, &region).is_err());
    }
}
