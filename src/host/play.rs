//! `cargo play`: the game in a terminal.
//!
//! ```text
//! cargo play                      # the built-in levels, from the first
//! cargo play -- --level cavern    # a built-in level by name, or a level file
//! cargo play -- --generate 7 --storeys 2   # a generated maze, then the built-in ones
//! cargo play -- --race            # race another terminal (the same command) on UDP
//! ```
//!
//! Each level's best winning run is kept as a ghost in `target/ghosts/`
//! (`--ghosts DIR`; [`super::ghost_file`]) and replayed, bit for bit, as a dim
//! marble beside the next attempts.
//!
//! The LED matrix is drawn with two shaded block characters per pixel, coloured by
//! brightness (the same [`crate::render`] frames the firmware shows: one pixel per
//! tile, the whole level when it fits the terminal, otherwise the largest window
//! that fits, following the marble). The keys stand in for the accelerometer: each
//! press of an arrow key (or W A S D) tilts the held reading 100 mg further that
//! way, up to ±500 mg per axis; space levels the board. `r` restarts, `n` goes to the next
//! level, `p` hands the board to the autopilot (and back), `q` / Esc / Ctrl-C quit.
//!
//! The game runs at its own frame rate (128 frames/s, [`FRAME_HZ`]) in real
//! time, through the firmware's own game loop step ([`Player::tick`]) and key
//! code ([`KeyTilt`]), with [`SYNTHETIC_TILT`] (a held key repeats the same
//! reading, which a real sensor never does): the same keys give the same
//! readings and the same game as in `cargo qemu`. The terminal is put in raw
//! mode on the alternate screen and restored on every way out: quitting, an
//! error, or a panic.

use std::boxed::Box;
use std::io::{self, IsTerminal, Write};
use std::path::{Path, PathBuf};
use std::string::{String, ToString};
use std::time::{Duration, Instant};
use std::vec::Vec;
use std::{eprintln, format};

use clap::Parser;
use crossterm::event::{self, Event, KeyCode, KeyEvent, KeyEventKind, KeyModifiers};
use crossterm::style::{Color, Print, ResetColor, SetForegroundColor};
use crossterm::terminal::{self, Clear, ClearType};
use crossterm::{cursor, execute, queue};

use super::ghost_file::{self, GhostKeeper, GhostRun};
use super::{load_level, Loaded};
use crate::game::level::LevelView;
use crate::game::levels::LEVELS;
use crate::game::rules::Phase;
use crate::game::session::SYNTHETIC_TILT;
use crate::input::event::InputEvent;
use crate::input::keys::{Key, KeyTilt};
use crate::matrix::MAX_BRIGHTNESS;
use crate::player::{Player, FRAME_HZ};
use crate::render::{blink_on, follow_axis, render_world, tile_point, Viewport};

/// The firmware's player. The terminal draws its own picture, sized to the
/// terminal, so the player's own renderer is a single pixel that is never
/// asked for.
pub(crate) type TerminalPlayer = Player<'static, 1, 1, true, true>;
/// Frames between two screen updates (128 / 4 = 32 updates per second).
const DRAW_EVERY: u32 = 4;
/// Lines under the matrix (status, tilt, help).
const HUD_LINES: u16 = 4;

/// Command-line arguments of `cargo play`.
#[derive(Parser, Debug)]
#[command(
    name = "play",
    version,
    about = "Play Marble Rolling in the terminal (arrow keys / WASD tilt the board)"
)]
pub struct Args {
    /// Level to start with: a built-in name or a level file (default: the first
    /// built-in level).
    #[arg(long, value_name = "NAME|FILE")]
    pub(crate) level: Option<String>,
    /// Start with the autopilot at the controls (`p` toggles it).
    #[arg(long)]
    pub(crate) autopilot: bool,
    /// A generated maze to start with instead of `--level`.
    #[command(flatten)]
    pub(crate) maze: super::generated::GenerateArgs,
    /// Where each level's best run is kept as a ghost (`NAME.ghost`).
    #[arg(long, value_name = "DIR", default_value = "target/ghosts")]
    pub(crate) ghosts: PathBuf,
    /// Race another terminal on this machine (UDP on localhost): start the
    /// same command in a second terminal. The maze is `--generate`'s (a new
    /// seed without it) of whichever side the handshake picks.
    #[arg(long, conflicts_with = "level")]
    pub race: bool,
    /// The race's channel: a pair of UDP ports (47400 + 2 N and the next).
    #[arg(long, value_name = "N", default_value_t = 0, requires = "race")]
    pub(crate) channel: u16,
}

/// Runs the player with `args`, the process arguments (the binary hands
/// `--race` to [`super::race::main`] instead); returns the exit status.
pub fn main(args: Args) -> i32 {
    let generated = match args.maze.level() {
        Ok(g) => g.map(|(_, view)| Loaded {
            view,
            builtin: None,
        }),
        Err(e) => {
            eprintln!("play: error: {e}");
            return 2;
        }
    };
    let first = match (&args.level, generated) {
        (_, Some(maze)) => maze,
        (Some(l), None) => match load_level(l) {
            Ok(l) => l,
            Err(e) => {
                eprintln!("play: error: {e}");
                return 2;
            }
        },
        (None, None) => Loaded {
            view: LEVELS[0],
            builtin: Some(0),
        },
    };
    if !io::stdin().is_terminal() || !io::stdout().is_terminal() {
        eprintln!(
            "play: error: standard input and output must be a terminal (an interactive game); \
             for a headless run use `cargo sim -- --level NAME`"
        );
        return 2;
    }
    let result = {
        let guard = match TerminalGuard::enter() {
            Ok(g) => g,
            Err(e) => {
                eprintln!("play: error: cannot set up the terminal: {e}");
                return 1;
            }
        };
        let r = Game::new(first, args.autopilot, &args.ghosts).and_then(|mut g| g.run());
        drop(guard);
        r
    };
    match result {
        Ok(()) => 0,
        Err(e) => {
            eprintln!("play: error: {e}");
            1
        }
    }
}

/// Raw mode + alternate screen + hidden cursor while alive; restored on drop and
/// by the panic hook.
pub(super) struct TerminalGuard;

impl TerminalGuard {
    pub(super) fn enter() -> io::Result<TerminalGuard> {
        terminal::enable_raw_mode()?;
        // From here on every way out restores the terminal.
        let guard = TerminalGuard;
        let previous = std::panic::take_hook();
        std::panic::set_hook(Box::new(move |info| {
            restore_terminal();
            previous(info);
        }));
        execute!(
            io::stdout(),
            terminal::EnterAlternateScreen,
            cursor::Hide,
            Clear(ClearType::All)
        )?;
        Ok(guard)
    }
}

impl Drop for TerminalGuard {
    fn drop(&mut self) {
        restore_terminal();
    }
}

fn restore_terminal() {
    let _ = execute!(
        io::stdout(),
        ResetColor,
        cursor::Show,
        terminal::LeaveAlternateScreen
    );
    let _ = terminal::disable_raw_mode();
}

/// The key a terminal key event stands for ([`KeyTilt`]'s keys, as the
/// firmware decodes them from raw bytes), or none.
pub fn key_of(event: KeyEvent) -> Option<Key> {
    if event.kind == KeyEventKind::Release {
        return None;
    }
    if event.modifiers.contains(KeyModifiers::CONTROL)
        && matches!(event.code, KeyCode::Char('c' | 'C'))
    {
        return Some(Key::Quit);
    }
    Some(match event.code {
        KeyCode::Left | KeyCode::Char('a' | 'A') => Key::Left,
        KeyCode::Right | KeyCode::Char('d' | 'D') => Key::Right,
        KeyCode::Up | KeyCode::Char('w' | 'W') => Key::Up,
        KeyCode::Down | KeyCode::Char('s' | 'S') => Key::Down,
        KeyCode::Char(' ') => Key::Level,
        KeyCode::Char('r' | 'R') => Key::Restart,
        KeyCode::Char('n' | 'N') => Key::Next,
        KeyCode::Char('c' | 'C') => Key::Calibrate,
        KeyCode::Char('p' | 'P') => Key::Autopilot,
        KeyCode::Char('q' | 'Q') | KeyCode::Esc => Key::Quit,
        _ => return None,
    })
}

/// The level list `cargo play` cycles through: the chosen level file, if
/// any, then the built-in levels. Leaked: the player's session borrows its
/// level for the whole run, as the firmware's borrows flash.
fn level_list(first: Loaded) -> (&'static [LevelView<'static>], usize) {
    match first.builtin {
        Some(index) => (&LEVELS, index),
        None => {
            let mut list = Vec::with_capacity(LEVELS.len() + 1);
            list.push(first.view);
            list.extend_from_slice(&LEVELS);
            (Vec::leak(list), 0)
        }
    }
}

struct Game {
    player: TerminalPlayer,
    keys: KeyTilt,
    /// The viewport's origin (tile shown top left) while the level does not fit.
    view: Option<(i32, i32)>,
    shown_level: usize,
    out: io::Stdout,
    buf: Vec<u8>,
    ghosts: PathBuf,
    /// The level the keeper and the ghost are for, the keeper, the stored
    /// ghost's replay, and the last word about ghosts for the status line.
    ghost_level: Option<usize>,
    keeper: GhostKeeper,
    ghost: Option<GhostRun>,
    ghost_note: String,
}

/// The ghost marble's brightness (the live marble is drawn at full).
pub(super) const GHOST_BRIGHTNESS: u8 = 4;

impl Game {
    fn new(first: Loaded, autopilot: bool, ghosts: &Path) -> io::Result<Game> {
        let (levels, index) = level_list(first);
        let player =
            TerminalPlayer::new(levels, index, SYNTHETIC_TILT, autopilot).map_err(|e| {
                io::Error::new(
                    io::ErrorKind::InvalidData,
                    format!("level `{}` cannot be set up: {e}", first.view.info.name),
                )
            })?;
        Ok(Game {
            shown_level: player.level_index(),
            player,
            keys: KeyTilt::new(),
            view: None,
            out: io::stdout(),
            buf: Vec::with_capacity(1 << 16),
            ghosts: ghosts.to_path_buf(),
            ghost_level: None,
            keeper: GhostKeeper::new(ghosts, "", SYNTHETIC_TILT, None),
            ghost: None,
            ghost_note: String::new(),
        })
    }

    /// Loads the ghost of the level on show when it changed, and keeps the
    /// attempt's readings (writing a new best run).
    fn follow_ghost(&mut self) {
        let index = self.player.level_index();
        if self.ghost_level != Some(index) {
            let level = *self.player.game().level();
            let (config, tilt) = (TerminalPlayer::CONFIG, SYNTHETIC_TILT);
            let stored = ghost_file::load(&self.ghosts, level, config, tilt);
            self.ghost = stored
                .as_deref()
                .and_then(|b| GhostRun::new(b, level, config, tilt));
            let best = self.ghost.as_ref().map(GhostRun::clock);
            self.keeper = GhostKeeper::new(&self.ghosts, level.info.name, tilt, best);
            self.ghost_level = Some(index);
            self.ghost_note = match best {
                Some(f) => format!("ghost: best {:.2} s", f as f64 / FRAME_HZ as f64),
                None => "no ghost yet: win to leave one".to_string(),
            };
        }
        match self.keeper.observe(self.player.session()) {
            Ok(Some(path)) => {
                let level = *self.player.game().level();
                let (config, tilt) = (TerminalPlayer::CONFIG, SYNTHETIC_TILT);
                self.ghost = ghost_file::load(&self.ghosts, level, config, tilt)
                    .and_then(|b| GhostRun::new(&b, level, config, tilt));
                self.ghost_note = format!("new best run: ghost saved to {}", path.display());
            }
            Ok(None) => {}
            Err(e) => self.ghost_note = format!("ghost not saved: {e}"),
        }
    }

    fn run(&mut self) -> io::Result<()> {
        let period = Duration::from_secs(1) / FRAME_HZ;
        let mut next = Instant::now();
        let mut frame = 0u32;
        self.draw()?;
        loop {
            let now = Instant::now();
            if now < next {
                if event::poll(next - now)? {
                    match event::read()? {
                        Event::Key(k) => {
                            if let Some(key) = key_of(k) {
                                if !self.key(key) {
                                    return Ok(());
                                }
                                self.draw()?;
                            }
                        }
                        Event::Resize(..) => {
                            self.view = None;
                            execute!(self.out, Clear(ClearType::All))?;
                            self.draw()?;
                        }
                        _ => {}
                    }
                }
                continue;
            }
            self.player.tick(self.keys.tilt(), false);
            self.follow_ghost();
            if self.player.level_index() != self.shown_level || self.player.game().frames() == 0 {
                // Another level, or the same one restarted: a new picture.
                self.shown_level = self.player.level_index();
                self.view = None;
            }
            frame = frame.wrapping_add(1);
            if frame.is_multiple_of(DRAW_EVERY) {
                self.draw()?;
            }
            next += period;
            // Fell far behind (a suspended terminal): carry on from now, no catching up.
            if now.saturating_duration_since(next) > Duration::from_millis(250) {
                next = now;
            }
        }
    }

    /// Applies a key; `false` to quit.
    fn key(&mut self, key: Key) -> bool {
        match self.keys.press(key) {
            // The tilt is read by every tick.
            InputEvent::Tilt(_) => true,
            event => self.player.handle(event),
        }
    }

    /// The matrix image with the ghost, dim, where it is on the storey on show.
    fn picture(&mut self, cols: u16, rows: u16) -> Picture {
        let game = self.player.game();
        let mut pic = Picture::of(game, &mut self.view, cols, rows.saturating_sub(HUD_LINES));
        if let Some((i, k, s)) = self.ghost.as_mut().and_then(|g| g.at(game)) {
            pic.dim(i, k, s);
        }
        pic
    }

    fn draw(&mut self) -> io::Result<()> {
        let (cols, rows) = terminal::size().unwrap_or((80, 24));
        let pic = self.picture(cols, rows);
        let h = pic.rows();
        let b = &mut self.buf;
        b.clear();
        pic.queue(b)?;
        let game = self.player.game();
        let info = &game.level().info;
        let hz = game.config().frame_hz() as f64;
        let t = game.clock_frames() as f64 / hz;
        let which = format!("level {}", self.player.level_index() + 1);
        let status = match game.phase() {
            Phase::Playing => format!("{:.1} / {} s", t, info.time_limit_s),
            Phase::Won => format!("WON in {t:.2} s!"),
            Phase::Fell => "FELL into a hole: again".to_string(),
            Phase::TimeUp => "TIME'S UP: again".to_string(),
        };
        let reading = self.player.session().reading();
        let pilot = if self.player.autopilot() {
            "  [autopilot]"
        } else {
            ""
        };
        let lines = [
            format!("{} ({which})  {status}  · {}", info.name, self.ghost_note),
            format!(
                "tilt  x {:+5} mg  z {:+5} mg{pilot}",
                -reading.x, -reading.z
            ),
            "arrows/WASD tilt · space level · c calibrate · r restart · n next · p autopilot · q quit"
                .to_string(),
        ];
        for (i, l) in lines.iter().enumerate() {
            let shown: String = l.chars().take(cols as usize).collect();
            queue!(
                b,
                cursor::MoveTo(0, (h + 1 + i) as u16),
                Print(shown),
                Clear(ClearType::UntilNewLine)
            )?;
        }
        self.out.write_all(b)?;
        self.out.flush()
    }
}

/// Two characters per pixel, denser for brighter pixels (readable without colour).
pub(super) fn shade(v: u8) -> &'static str {
    match v {
        0 => "  ",
        1..=2 => "░░",
        3..=5 => "▒▒",
        6..=10 => "▓▓",
        _ => "██",
    }
}

/// The matrix as the terminal shows it: the whole level, one pixel per tile, or
/// where it does not fit a window that follows the marble (the renderer's
/// viewport rule, sized to the terminal). `cargo play` and the race draw it.
pub(super) struct Picture {
    w: usize,
    h: usize,
    /// The window's first column and row (tiles).
    origin: (i32, i32),
    /// The storey of the marble followed, if one is in play.
    storey: Option<i32>,
    /// `w × h` brightness levels, row by row.
    px: Vec<u8>,
}

impl Picture {
    /// `game`'s maze in `cols × rows` character cells, two to a pixel; `view`
    /// is the window kept from the last picture (the viewport moves only when
    /// the marble nears its edge).
    pub(super) fn of(
        game: &crate::game::rules::Game<'_, crate::physics::Fx>,
        view: &mut Option<(i32, i32)>,
        cols: u16,
        rows: u16,
    ) -> Self {
        const N: usize = 128;
        let level = game.level();
        let (nx, nz) = (level.info.nx as i32, level.info.nz as i32);
        let w = nx.min(cols as i32 / 2).max(1);
        let h = nz.min(rows as i32).max(1);
        let layout = &game.world().params().layout;
        let live = game.world().marbles().iter().find(|m| !m.out);
        let focus = live.map(|m| tile_point(layout, m.pos.x, m.pos.z).tile());
        let vx = follow_axis(view.map(|v| v.0), nx, w, focus.map(|f| f.0));
        let vz = follow_axis(view.map(|v| v.1), nz, h, focus.map(|f| f.1));
        *view = Some((vx, vz));
        let blink = blink_on(game.frames(), game.config().frame_log2);
        let frame: crate::matrix::Frame<N, N> =
            render_world(level, game.world(), blink, Viewport::new(vx, vz));
        let (w, h) = (w as usize, h as usize);
        let px = frame
            .rows()
            .iter()
            .take(h)
            .flat_map(|r| r[..w].iter().copied())
            .collect();
        Picture {
            w,
            h,
            origin: (vx, vz),
            storey: live.map(|m| layout.storey_of(m.pos.y)),
            px,
        }
    }

    /// Rows drawn.
    pub(super) fn rows(&self) -> usize {
        self.h
    }

    /// A second marble (a ghost, an opponent) at tile `(i, k)` of storey `s`:
    /// dim, where it is on the storey on show and nothing brighter is.
    pub(super) fn dim(&mut self, i: i32, k: i32, s: i32) {
        let (x, y) = (i - self.origin.0, k - self.origin.1);
        if Some(s) == self.storey
            && (0..self.w as i32).contains(&x)
            && (0..self.h as i32).contains(&y)
        {
            let p = &mut self.px[y as usize * self.w + x as usize];
            *p = (*p).max(GHOST_BRIGHTNESS);
        }
    }

    /// Queues the picture at the terminal's top left.
    pub(super) fn queue(&self, b: &mut Vec<u8>) -> io::Result<()> {
        let mut last: Option<u8> = None;
        for y in 0..self.h {
            queue!(b, cursor::MoveTo(0, y as u16))?;
            for x in 0..self.w {
                let v = self.px[y * self.w + x].min(MAX_BRIGHTNESS);
                if last != Some(v) {
                    queue!(b, SetForegroundColor(colour(v)))?;
                    last = Some(v);
                }
                queue!(b, Print(shade(v)))?;
            }
        }
        queue!(b, ResetColor)
    }
}

/// Amber, scaled by brightness.
pub(super) fn colour(v: u8) -> Color {
    let f = 0.15 + 0.85 * (v as f64 / MAX_BRIGHTNESS as f64).sqrt();
    Color::Rgb {
        r: (255.0 * f) as u8,
        g: (176.0 * f) as u8,
        b: (40.0 * f) as u8,
    }
}
