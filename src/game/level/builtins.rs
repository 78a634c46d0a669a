//! Built-in levels: [`builtin_level!`](crate::builtin_level) parses a level's
//! text at compile time into a `'static` [`LevelView`](super::LevelView) that
//! keeps only the name and the tiles in flash; a malformed one stops the build
//! with its line and column.

use crate::physics::geometry::grid::TileGrid;

#[doc(hidden)]
pub use const_panic as __const_panic;

/// A built-in level, parsed at compile time into a `'static` [`LevelView`](super::LevelView). A
/// malformed level stops the build with its line, column and what is wrong:
///
/// ```compile_fail
/// static BAD: marble_rolling::game::level::LevelView<'static> =
///     marble_rolling::builtin_level!("---\n#####\n#SxG#\n#####\n");
/// // error: built-in level: line 3, column 3: unknown tile (use # . O S G)
/// ```
///
/// ```
/// static OK: marble_rolling::game::level::LevelView<'static> =
///     marble_rolling::builtin_level!("---\n#####\n#S.G#\n#####\n");
/// assert_eq!(OK.info.goals(), &[marble_rolling::game::level::Cell::new(3, 1, 0)]);
/// ```
#[macro_export]
macro_rules! builtin_level {
    ($src:expr) => {{
        const SRC: &str = $src;
        const LEVEL: $crate::game::level::Level<
            'static,
            { $crate::game::level::words_needed(SRC) },
        > = match $crate::game::level::parse(SRC) {
            Ok(l) => l,
            Err(e) => $crate::game::level::__const_panic::concat_panic!(
                "built-in level: line ",
                e.line,
                ", column ",
                e.column,
                ": ",
                e.kind.message(),
                if e.kind.detail().is_empty() { "" } else { ": " },
                e.kind.detail()
            ),
        };
        // The name and the grid get constants of their own: the view must not
        // point into `SRC` or into `LEVEL` (whose name does), or the level's
        // whole text stays in flash (about 2 KB for the built-in levels).
        const NAME_BYTES: [u8; LEVEL.info.name.len()] =
            $crate::game::level::name_bytes(LEVEL.info.name);
        const NAME: &str = match ::core::str::from_utf8(&NAME_BYTES) {
            Ok(name) => name,
            Err(_) => panic!("built-in level: the name is not UTF-8"),
        };
        const GRID: $crate::game::level::BuiltinGrid<{ $crate::game::level::words_needed(SRC) }> =
            LEVEL.grid;
        let mut info = LEVEL.info;
        info.name = NAME;
        $crate::game::level::LevelView {
            info,
            tiles: GRID.view(),
        }
    }};
}

/// The grid of a built-in level ([`builtin_level!`]).
#[doc(hidden)]
pub type BuiltinGrid<const WORDS: usize> = TileGrid<WORDS>;

/// `name`'s bytes in an array of their own ([`builtin_level!`]): `N` must be
/// `name.len()`.
#[doc(hidden)]
pub const fn name_bytes<const N: usize>(name: &str) -> [u8; N] {
    let bytes = name.as_bytes();
    let mut out = [0u8; N];
    let mut n = 0;
    while n < N && n < bytes.len() {
        out[n] = bytes[n];
        n += 1;
    }
    out
}
