use marble_rolling::game::generate::generate;
use marble_rolling::player::FRAME_HZ;

use crate::game_loop::{
    clock_frames, finished_count, finished_frames, finished_ghost_len, finished_hash,
    finished_phase, init, phase, set_autopilot, set_tilt, ticks,
};
use crate::ghost::{
    ghost_active, ghost_clock_frames, ghost_frames, ghost_in_ptr, ghost_phase, ghost_record,
    ghost_state_hash, load_ghost, record_ptr,
};
use crate::maze::{level_is_generated, play_generated};
use crate::storage::{
    check_level, source_text_len, source_text_ptr, OUT, TEXT, TEXT_CAPACITY, TEXT_CUT,
};

/// The answer [`check_level`] gives for `bytes` in the text buffer ("" for ok).
fn checked_message(bytes: &[u8]) -> String {
    // SAFETY: one test, one thread: nothing else touches TEXT or OUT.
    let text: &mut [u8; TEXT_CAPACITY] = unsafe { &mut *TEXT.0.get() };
    text[..bytes.len()].copy_from_slice(bytes);
    let len = check_level(bytes.len() as u32) as usize;
    String::from_utf8(OUT.0.borrow().bytes[..len].to_vec()).unwrap()
}

/// The buffers are statics, and the harness runs tests in parallel: one at a time.
static SERIAL: std::sync::Mutex<()> = std::sync::Mutex::new(());

#[test]
fn messages_name_line_column_bytes_and_ranges() {
    let _alone = SERIAL.lock().unwrap_or_else(|e| e.into_inner());
    assert_eq!(checked_message(b"---\n#####\n#S.G#\n#####\n"), "");
    assert_eq!(
        checked_message(b"name: a\n---\n#####\n#S\xffG#\n#####\n"),
        "4:3: not UTF-8 (byte 0xFF)"
    );
    // A character cut short at the end is reported at its first byte.
    assert_eq!(
        checked_message("name: é".as_bytes().split_last().unwrap().1),
        "1:7: not UTF-8 (byte 0xC3)"
    );
    assert_eq!(
        checked_message(b"restitution: 1.5\n---\n#####\n#S.G#\n#####\n"),
        "1:14: value out of range: restitution is 0 ..= 1"
    );
    assert_eq!(
        checked_message(&[b'a'; TEXT_CAPACITY]),
        "2:1: no `---` line between header and grid"
    );
    // One byte more than the buffer: the length alone says it.
    assert_eq!(
        {
            let len = check_level(TEXT_CAPACITY as u32 + 1) as usize;
            String::from_utf8(OUT.0.borrow().bytes[..len].to_vec()).unwrap()
        },
        format!(
            "1:1: longer than {TEXT_CAPACITY} bytes, more than a level of 127 × 127 tiles \
             on 4 storeys takes"
        )
    );
}

/// A text too long for the buffer: the parser's first error in the lines
/// that fit (a grid wider than 127 tiles), else the length and why; the
/// largest level the format takes fits.
#[test]
fn a_text_too_long_names_its_first_error_or_the_largest_level() {
    let _alone = SERIAL.lock().unwrap_or_else(|e| e.into_inner());
    let cut = |text: &str| {
        let fits = &text[..TEXT_CAPACITY];
        let fits = &fits[..fits.rfind('\n').map_or(0, |n| n + 1)];
        // SAFETY: one test at a time (SERIAL).
        let buf: &mut [u8; TEXT_CAPACITY] = unsafe { &mut *TEXT.0.get() };
        buf[..fits.len()].copy_from_slice(fits.as_bytes());
        let len = check_level(fits.len() as u32 | TEXT_CUT) as usize;
        String::from_utf8(OUT.0.borrow().bytes[..len].to_vec()).unwrap()
    };
    let grid = |nx: usize, nz: usize| {
        let mut rows = vec![".".repeat(nx - 2); nz - 2];
        rows[0].replace_range(0..1, "S");
        rows[nz - 3].replace_range(nx - 3..nx - 2, "G");
        let wall = "#".repeat(nx);
        let mut text = format!("{wall}\n");
        for row in rows {
            text += &format!("#{row}#\n");
        }
        text + &wall + "\n"
    };
    let wide = format!("name: wide\n---\n{}", grid(401, 201));
    assert!(wide.len() > TEXT_CAPACITY, "{} bytes", wide.len());
    assert_eq!(cut(&wide), "3:1: grid larger than 127 tiles");
    // No error in the lines that fit (the header has not even ended): the length, and why.
    let padded = format!(
        "name: padded\n{}---\n{}",
        "\n".repeat(TEXT_CAPACITY),
        grid(5, 5)
    );
    assert_eq!(
        cut(&padded),
        format!(
            "1:1: longer than {TEXT_CAPACITY} bytes, more than a level of 127 × 127 tiles \
             on 4 storeys takes"
        )
    );
    let storey = grid(127, 127);
    let largest = format!("name: largest\n---\n{storey}===\n{storey}===\n{storey}===\n{storey}")
        .replace('\n', "\r\n");
    assert!(largest.len() <= TEXT_CAPACITY, "{} bytes", largest.len());
    assert_eq!(checked_message(largest.as_bytes()), "");
}

/// The page's round trip, natively (with overflow checks): a generated
/// maze's autopilot win is recorded, handed back as the stored ghost,
/// replayed beside the next attempt to the win's hash; a ghost with one
/// byte changed is refused.
#[test]
fn ghost_of_a_generated_maze_replays_to_its_hash() {
    let _alone = SERIAL.lock().unwrap_or_else(|e| e.into_inner());
    assert_eq!(init(), 1);
    assert_eq!(play_generated(7, 6, 2, 2), 0);
    // SAFETY: one test at a time; the page reads these buffers the same way.
    let text = unsafe {
        std::slice::from_raw_parts(source_text_ptr(), source_text_len() as usize).to_vec()
    };
    let maze = generate(7, 6, 2, 2).unwrap().to_string();
    assert_eq!(String::from_utf8(text).unwrap(), maze);
    set_autopilot(1);
    let count = finished_count();
    ticks(4000 * FRAME_HZ, 1);
    assert_eq!((finished_count(), finished_phase()), (count + 1, 1));
    let (frames, hash) = (finished_frames(), finished_hash());
    let len = finished_ghost_len() as usize;
    assert!(len > 24, "{len} bytes");
    // SAFETY: as above.
    let ghost = unsafe { std::slice::from_raw_parts(record_ptr(), len).to_vec() };
    set_autopilot(0);
    // The win's pause, then the maze again.
    ticks(FRAME_HZ + 1, 0);
    assert_eq!((level_is_generated(), crate::game_loop::frames()), (1, 0));
    let load = |bytes: &[u8]| {
        // SAFETY: as above.
        unsafe { std::ptr::copy_nonoverlapping(bytes.as_ptr(), ghost_in_ptr(), bytes.len()) };
        load_ghost(bytes.len() as u32)
    };
    assert_eq!(load(&ghost), 0);
    // Two seconds of looking at the maze: the ghost waits at its start
    // (its own looking played, its clock at 0) for the player's first tilt.
    let idle = ghost_record(2);
    ticks(2 * FRAME_HZ, 0);
    assert_eq!((phase(), clock_frames()), (0, 0));
    assert_eq!(
        (ghost_phase(), ghost_frames(), ghost_clock_frames()),
        (0, idle, 0)
    );
    // Then a nudge starts the player's clock (the board levelled again at
    // once: the marble soon stops, the clock runs on): the ghost races
    // from there, clock for clock, to the record's end, frames and hash.
    set_tilt(300, 0);
    ticks(16, 1);
    set_tilt(0, 0);
    assert!(clock_frames() > 0);
    for _ in 0..frames {
        ticks(1, 1);
        assert_eq!(phase(), 0);
        if ghost_phase() != 0 {
            break;
        }
        assert_eq!(ghost_clock_frames(), clock_frames());
    }
    assert_eq!(
        (ghost_phase(), ghost_frames(), ghost_state_hash()),
        (1, frames, hash)
    );
    let mut other = ghost.clone();
    let last = other.len() - 1;
    other[last] ^= 1;
    assert_ne!(load(&other), 0);
    assert_eq!(ghost_active(), 0);
}
