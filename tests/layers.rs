//! The crate's layers point one way: every `crate::` and `super::` path in
//! `src/` (outside `src/bin`, which is other crates) may only reach a module
//! on its own layer or one below, and no two modules may reach each other
//! through a loop of such paths.
//!
//! The layers, lowest first, are [`LAYERS`]; docs/architecture.md draws them.
//! A module takes the layer of the longest prefix listed. Paths are read from
//! the source with its comments removed, so doc links do not count: a doc may
//! point anywhere, the code may not.

use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;

/// Module-path prefixes and their layer, lowest first. The player runs the
/// game loop above the picture and the sound it drives, so `player`
/// sits above `render` and `sound`, which read the rules and levels below.
const LAYERS: &[(&str, u8)] = &[
    ("physics", 0),
    ("input", 1),
    ("game", 2),
    ("matrix", 3),
    ("race", 3),
    ("render", 4),
    ("sound", 4),
    ("player", 5),
    ("records", 6),
    ("board", 7),
    ("app", 8),
    ("study", 9),
    ("host", 10),
];

/// `module → source` for every module file under `src/`.
fn sources(root: &Path) -> BTreeMap<String, String> {
    let mut out = BTreeMap::new();
    let mut stack = vec![root.to_path_buf()];
    while let Some(dir) = stack.pop() {
        for entry in std::fs::read_dir(&dir).expect("src/ readable") {
            let path = entry.expect("entry").path();
            let rel = path.strip_prefix(root).expect("under src/");
            if path.is_dir() {
                if rel != Path::new("bin") {
                    stack.push(path);
                }
                continue;
            }
            if path.extension().is_none_or(|e| e != "rs") {
                continue;
            }
            let mut parts: Vec<String> = rel
                .with_extension("")
                .iter()
                .map(|p| p.to_string_lossy().into_owned())
                .collect();
            if parts.last().is_some_and(|p| p == "mod" || p == "lib") {
                parts.pop();
            }
            let text = std::fs::read_to_string(&path).expect("source readable");
            out.insert(parts.join("::"), text);
        }
    }
    out
}

/// `text` without its `//` and `/* */` comments and string literals.
fn code(text: &str) -> String {
    let b = text.as_bytes();
    let mut out = String::with_capacity(text.len());
    let mut i = 0;
    while i < b.len() {
        if b[i..].starts_with(b"//") {
            while i < b.len() && b[i] != b'\n' {
                i += 1;
            }
        } else if b[i..].starts_with(b"/*") {
            let mut depth = 0;
            while i < b.len() {
                if b[i..].starts_with(b"/*") {
                    depth += 1;
                    i += 2;
                } else if b[i..].starts_with(b"*/") {
                    depth -= 1;
                    i += 2;
                    if depth == 0 {
                        break;
                    }
                } else {
                    i += 1;
                }
            }
        } else if b[i] == b'"' && (i == 0 || b[i - 1] != b'\'') {
            i += 1;
            while i < b.len() && b[i] != b'"' {
                i += if b[i] == b'\\' { 2 } else { 1 };
            }
            i += 1;
        } else {
            out.push(b[i] as char);
            i += 1;
        }
    }
    out
}

fn is_ident(c: u8) -> bool {
    c.is_ascii_alphanumeric() || c == b'_'
}

/// The paths of the use tree at `s[*i..]` (after `crate::` or `super::`),
/// each as its segments, appended to `prefix`.
fn tree(s: &[u8], i: &mut usize, prefix: &[String], out: &mut Vec<Vec<String>>) {
    let mut path = prefix.to_vec();
    loop {
        while *i < s.len() && s[*i].is_ascii_whitespace() {
            *i += 1;
        }
        if *i < s.len() && s[*i] == b'{' {
            *i += 1;
            loop {
                tree(s, i, &path, out);
                while *i < s.len() && s[*i].is_ascii_whitespace() {
                    *i += 1;
                }
                match s.get(*i) {
                    Some(b',') => *i += 1,
                    Some(b'}') => {
                        *i += 1;
                        return;
                    }
                    _ => return,
                }
                while *i < s.len() && s[*i].is_ascii_whitespace() {
                    *i += 1;
                }
                if s.get(*i) == Some(&b'}') {
                    *i += 1;
                    return;
                }
            }
        }
        let start = *i;
        while *i < s.len() && is_ident(s[*i]) {
            *i += 1;
        }
        if *i > start {
            let seg = String::from_utf8_lossy(&s[start..*i]).into_owned();
            if seg != "self" {
                path.push(seg);
            }
        }
        if s[*i..].starts_with(b"::") {
            *i += 2;
        } else {
            out.push(path);
            return;
        }
    }
}

/// The modules `module`'s code reaches, resolved to the deepest module file
/// each path names.
fn reaches(module: &str, text: &str, modules: &BTreeSet<String>) -> BTreeSet<String> {
    let code = code(text);
    let s = code.as_bytes();
    let here: Vec<String> = module
        .split("::")
        .filter(|p| !p.is_empty())
        .map(String::from)
        .collect();
    let mut paths = Vec::new();
    let mut i = 0;
    while i < s.len() {
        let boundary = i == 0 || !(is_ident(s[i - 1]) || s[i - 1] == b':' || s[i - 1] == b'$');
        if boundary && s[i..].starts_with(b"crate::") {
            i += 7;
            tree(s, &mut i, &[], &mut paths);
        } else if boundary && s[i..].starts_with(b"super::") {
            let mut base = here.clone();
            while s[i..].starts_with(b"super::") {
                base.pop();
                i += 7;
            }
            tree(s, &mut i, &base, &mut paths);
        } else {
            i += 1;
        }
    }
    let mut out = BTreeSet::new();
    for path in paths {
        let mut n = path.len();
        while n > 0 && !modules.contains(&path[..n].join("::")) {
            n -= 1;
        }
        let target = path[..n].join("::");
        let below_here = target.starts_with(&format!("{module}::")) || module.is_empty();
        if target != module && !target.is_empty() && !below_here {
            out.insert(target);
        }
    }
    out
}

fn layer(module: &str) -> Option<u8> {
    LAYERS
        .iter()
        .filter(|(p, _)| module == *p || module.starts_with(&format!("{p}::")))
        .max_by_key(|(p, _)| p.len())
        .map(|&(_, l)| l)
}

/// Every back arrow (a path to a higher layer), every module without a layer,
/// and every loop, as messages; empty when the layers hold.
fn violations(sources: &BTreeMap<String, String>) -> Vec<String> {
    let modules: BTreeSet<String> = sources.keys().cloned().collect();
    let mut errors = Vec::new();
    let mut graph: BTreeMap<&str, BTreeSet<String>> = BTreeMap::new();
    for (module, text) in sources {
        if module.is_empty() {
            continue;
        }
        let Some(from) = layer(module) else {
            errors.push(format!("{module}: no layer in LAYERS"));
            continue;
        };
        let targets = reaches(module, text, &modules);
        for target in &targets {
            // A module may use its parent's items; the parent's own layer decides.
            if module.starts_with(&format!("{target}::")) {
                continue;
            }
            match layer(target) {
                Some(to) if to > from => {
                    errors.push(format!("{module} (layer {from}) → {target} (layer {to})"))
                }
                _ => {}
            }
        }
        graph.insert(module, targets);
    }
    // Loops: a module that reaches itself again through others.
    for &start in graph.keys() {
        let mut seen = BTreeSet::new();
        let mut stack: Vec<(String, Vec<String>)> = graph[start]
            .iter()
            .map(|t| (t.clone(), vec![start.to_string(), t.clone()]))
            .collect();
        while let Some((node, trail)) = stack.pop() {
            if node == start {
                errors.push(format!("loop: {}", trail.join(" → ")));
                break;
            }
            if !seen.insert(node.clone()) {
                continue;
            }
            for next in graph.get(node.as_str()).into_iter().flatten() {
                let mut t = trail.clone();
                t.push(next.clone());
                stack.push((next.clone(), t));
            }
        }
    }
    errors
}

#[test]
fn imports_point_down_the_layers_and_close_no_loop() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let errors = violations(&sources(&root));
    assert!(
        errors.is_empty(),
        "layer violations:\n{}",
        errors.join("\n")
    );
}

/// The boards, each a folder of `src/board/` (its safe half) and the firmware
/// crates under `boards/` that run it. What more than one board uses lives in
/// `src/board/` outside every board's folder (the bus clear, the watchdog gate,
/// the virtual chips, the game's sizes), so that a board is described in its
/// own folder and no board's folder reaches another's, directly or through a
/// shared part.
const BOARDS: &[(&str, &[&str])] = &[
    ("board::qemu", &["qemu", "qemu-race"]),
    ("board::microbit", &["microbit"]),
    ("board::microbit_v1", &["microbit-v1"]),
];

/// The boards other than `own` that `module`'s code reaches. A firmware
/// crate's source is read with its paths into the library (`marble_rolling::`)
/// as the library's own (`crate::`), its own `crate::` paths set aside.
fn other_boards(own: &str, module: &str, text: &str, modules: &BTreeSet<String>) -> Vec<String> {
    reaches(module, text, modules)
        .into_iter()
        .filter_map(|target| {
            BOARDS
                .iter()
                .map(|(board, _)| *board)
                .find(|&board| {
                    board != own && (target == board || target.starts_with(&format!("{board}::")))
                })
                .map(|board| format!("{target} ({board})"))
        })
        .collect()
}

/// Every path from one board's code into another board's, as messages; and
/// from a shared part of `board` (outside every board's folder) into any
/// board's, since through it one board would reach another.
fn board_crossings(
    sources: &BTreeMap<String, String>,
    firmware: &[(String, String)],
) -> Vec<String> {
    let modules: BTreeSet<String> = sources.keys().cloned().collect();
    let mut errors = Vec::new();
    for (module, text) in sources {
        let own = match BOARDS
            .iter()
            .find(|(board, _)| module == board || module.starts_with(&format!("{board}::")))
        {
            Some((own, _)) => *own,
            // A shared part: no board is its own.
            None if module.starts_with("board::") => "",
            None => continue,
        };
        for crossing in other_boards(own, module, text, &modules) {
            errors.push(format!("{module} → {crossing}"));
        }
    }
    for (krate, text) in firmware {
        let Some((own, _)) = BOARDS
            .iter()
            .find(|(_, crates)| crates.contains(&krate.as_str()))
        else {
            continue;
        };
        let text = code(text)
            .replace("crate::", "firmware_crate::")
            .replace("marble_rolling::", "crate::");
        for crossing in other_boards(own, "firmware", &text, &modules) {
            errors.push(format!("boards/{krate} → {crossing}"));
        }
    }
    errors
}

/// Every `.rs` file under `boards/NAME/src`, as (NAME, source).
fn firmware_sources(root: &Path) -> Vec<(String, String)> {
    let mut out = Vec::new();
    for entry in std::fs::read_dir(root.join("boards")).expect("boards/ readable") {
        let name = entry
            .expect("entry")
            .file_name()
            .to_string_lossy()
            .into_owned();
        let mut paths = Vec::new();
        rust_files(root, &format!("boards/{name}/src"), &mut paths);
        for path in paths {
            let text = std::fs::read_to_string(root.join(path)).expect("source readable");
            out.push((name.clone(), text));
        }
    }
    out
}

#[test]
fn no_board_imports_another() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let sources = sources(&root.join("src"));
    for (board, _) in BOARDS {
        assert!(sources.contains_key(*board), "{board} is no module of src/");
    }
    let errors = board_crossings(&sources, &firmware_sources(root));
    assert!(errors.is_empty(), "board crossings:\n{}", errors.join("\n"));
}

/// The virtual chips (models of a board's parts that host tests and QEMU run
/// the real drivers against) know the input's frames and faults, never the
/// game: the same model serves any game.
const VIRTUAL_CHIPS: &[&str] = &[
    "board::virtual_lsm303agr",
    "board::qemu::virtual_i2c",
    "board::qemu::virtual_matrix",
    "board::microbit_v1::virtual_nxp",
    "board::microbit_v1::virtual_twi",
];

/// What the virtual chips may not reach.
const ABOVE_THE_CHIPS: &[&str] = &["game", "player", "render", "sound", "records", "app"];

#[test]
fn the_virtual_chips_import_no_game() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let sources = sources(&root);
    let modules: BTreeSet<String> = sources.keys().cloned().collect();
    let mut errors = Vec::new();
    for chip in VIRTUAL_CHIPS {
        assert!(sources.contains_key(*chip), "{chip} is no module of src/");
        for (module, text) in sources
            .iter()
            .filter(|(m, _)| *m == chip || m.starts_with(&format!("{chip}::")))
        {
            for target in reaches(module, text, &modules) {
                if ABOVE_THE_CHIPS
                    .iter()
                    .any(|up| target == *up || target.starts_with(&format!("{up}::")))
                {
                    errors.push(format!("{module} → {target}"));
                }
            }
        }
    }
    assert!(
        errors.is_empty(),
        "virtual chips reaching the game:\n{}",
        errors.join("\n")
    );
}

/// The check can fail: a board's module or a board's firmware crate reaching
/// another board is reported, and so is a shared part of `board` reaching a
/// board; a board reaching a shared part is not.
#[test]
fn the_board_check_reports_a_crossing() {
    let sources: BTreeMap<String, String> = [
        ("board", ""),
        ("board::i2c", ""),
        (
            "board::qemu",
            "use crate::board::i2c::Recovering; use crate::board::microbit::AXIS_MAP;",
        ),
        ("board::microbit", ""),
        ("board::microbit_v1", "use super::i2c::ClearBus;"),
        ("board::game_sizes", "use super::qemu::WIDTH;"),
    ]
    .iter()
    .map(|(m, t)| (m.to_string(), t.to_string()))
    .collect();
    let firmware = [(
        "microbit-v1".to_string(),
        "use marble_rolling::board::microbit::Task; // marble_rolling::board::qemu in a comment"
            .to_string(),
    )];
    assert_eq!(
        board_crossings(&sources, &firmware),
        [
            "board::game_sizes → board::qemu (board::qemu)",
            "board::qemu → board::microbit (board::microbit)",
            "boards/microbit-v1 → board::microbit (board::microbit)",
        ]
    );
}

/// The longest a source file outside `tests/` may be, in lines: a file over
/// it holds more than one concept.
const MAX_LINES: usize = 600;

/// Every `.rs` file under `dir`, as a path relative to `root`, `target/` left out.
fn rust_files(root: &Path, dir: &str, out: &mut Vec<String>) {
    let mut stack = vec![root.join(dir)];
    while let Some(dir) = stack.pop() {
        let Ok(entries) = std::fs::read_dir(&dir) else {
            continue;
        };
        for entry in entries {
            let path = entry.expect("entry").path();
            if path.is_dir() {
                if path.file_name().is_some_and(|n| n != "target") {
                    stack.push(path);
                }
            } else if path.extension().is_some_and(|e| e == "rs") {
                let rel = path.strip_prefix(root).expect("under the root");
                out.push(rel.to_string_lossy().replace('\\', "/"));
            }
        }
    }
}

/// The files of `files` (path, lines) over [`MAX_LINES`].
fn too_long(files: &[(String, usize)]) -> Vec<String> {
    files
        .iter()
        .filter(|(_, lines)| *lines > MAX_LINES)
        .map(|(path, lines)| format!("{path}: {lines} lines, over {MAX_LINES}"))
        .collect()
}

#[test]
fn no_source_file_outside_tests_is_over_600_lines() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut paths = Vec::new();
    for dir in [
        "src",
        "boards",
        "xtask/src",
        "web/src",
        "study/src",
        "study/bench-m0/src",
        "benches",
    ] {
        rust_files(root, dir, &mut paths);
    }
    assert!(paths.iter().any(|p| p == "src/lib.rs"), "the tree was read");
    let files: Vec<(String, usize)> = paths
        .into_iter()
        .map(|path| {
            let text = std::fs::read_to_string(root.join(&path)).expect("source readable");
            let lines = text.lines().count();
            (path, lines)
        })
        .collect();
    let errors = too_long(&files);
    assert!(
        errors.is_empty(),
        "split by concept:\n{}",
        errors.join("\n")
    );
}

#[test]
fn the_length_check_reports_a_long_file() {
    let files = [
        ("src/a.rs".to_string(), 601),
        ("src/b.rs".to_string(), 600),
        ("web/src/c.rs".to_string(), 1_584),
    ];
    assert_eq!(
        too_long(&files),
        [
            "src/a.rs: 601 lines, over 600",
            "web/src/c.rs: 1584 lines, over 600"
        ]
    );
}

/// Each layer is a whole folder (or file) of `src/`: no module takes a layer
/// other than its folder's, so the floors can be read off the tree.
#[test]
fn every_layer_is_a_folder_of_src() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    for (prefix, _) in LAYERS {
        assert!(
            !prefix.contains("::"),
            "layer {prefix:?} is a module inside a folder: give it a folder of its own"
        );
        assert!(
            root.join(prefix).is_dir() || root.join(format!("{prefix}.rs")).is_file(),
            "layer {prefix:?} names no src/{prefix}/ and no src/{prefix}.rs"
        );
    }
}

/// The check can fail: a back arrow, a loop inside a layer and a module
/// outside every layer are each reported.
#[test]
fn the_check_reports_a_back_arrow_a_loop_and_a_stray_module() {
    let src = |pairs: &[(&str, &str)]| -> BTreeMap<String, String> {
        pairs
            .iter()
            .map(|(m, t)| (m.to_string(), t.to_string()))
            .collect()
    };
    let back = src(&[
        ("physics", "use crate::render::Renderer;"),
        ("render", "use crate::physics::Scalar;"),
    ]);
    let errors = violations(&back);
    assert!(
        errors
            .iter()
            .any(|e| e.starts_with("physics (layer 0) → render")),
        "{errors:?}"
    );

    let looped = src(&[
        ("input", ""),
        (
            "input::event",
            "use super::sensor::Fault; // crate::app in a comment",
        ),
        ("input::sensor", "use super::{event::InputEvent, tilt};"),
        ("input::tilt", ""),
    ]);
    let errors = violations(&looped);
    assert!(
        errors
            .iter()
            .any(|e| e.starts_with("loop: input::event → input::sensor")),
        "{errors:?}"
    );
    assert!(
        !errors.iter().any(|e| e.contains("app")),
        "comments do not count: {errors:?}"
    );

    let stray = src(&[("gadget", "")]);
    assert_eq!(violations(&stray), ["gadget: no layer in LAYERS"]);
}
