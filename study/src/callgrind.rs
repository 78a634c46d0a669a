//! Host instructions per step with `valgrind --tool=callgrind`: the study runs
//! itself as a child (`--callgrind-child SCENE ENGINE K`) that sets up one scene
//! and runs it once, with collection switched on only inside `run_plain` (ours or
//! the peer's), so setup, process start and the allocator's warm-up are not counted.

use std::path::Path;
use std::process::{Command, Stdio};

use marble_rolling::study::{Scene, SceneId};

use super::peer::{self, box2d::Box2d, rapier::Rapier};
use super::{host, Engine};

/// Whether valgrind is there.
pub fn available() -> bool {
    Command::new("valgrind")
        .arg("--version")
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .status()
        .is_ok_and(|s| s.success())
}

/// The child: one plain run. Prints the end state so that nothing is optimised out.
pub fn child(args: &[String]) -> Result<(), String> {
    let [scene, engine, k] = args else {
        return Err("usage: --callgrind-child SCENE ENGINE K".into());
    };
    let id = scene_by_name(scene).ok_or("unknown scene")?;
    let k: u32 = k.parse().map_err(|_| "bad K")?;
    match Engine::by_name(engine).ok_or("unknown engine")? {
        Engine::Ours(b) => println!("{:?}", host::plain(id, b, k, None)),
        Engine::Rapier => println!("{:?}", peer::plain::<Rapier>(id, k)),
        Engine::Box2d => println!("{:?}", peer::plain::<Box2d>(id, k)),
    }
    Ok(())
}

/// The scene called `name`.
pub fn scene_by_name(name: &str) -> Option<SceneId> {
    Scene::all()
        .into_iter()
        .find(|s| s.name == name)
        .map(|s| s.id)
}

/// Instructions per step of one configuration, counted by callgrind.
pub fn count(exe: &Path, scene: SceneId, engine: &str, k: u32, work: &Path) -> Result<f64, String> {
    let name = Scene::get(scene).name;
    let out = work.join(format!("callgrind.{name}.{engine}.{k}.out"));
    let status = Command::new("valgrind")
        .arg("--tool=callgrind")
        .arg(format!("--callgrind-out-file={}", out.display()))
        .arg("--toggle-collect=*run_plain*")
        .arg(exe)
        .args(["--callgrind-child", name, engine, &k.to_string()])
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .status()
        .map_err(|e| format!("valgrind: {e}"))?;
    if !status.success() {
        return Err(format!("valgrind exited with {status}"));
    }
    let text = std::fs::read_to_string(&out).map_err(|e| format!("{}: {e}", out.display()))?;
    let _ = std::fs::remove_file(&out);
    let total = text
        .lines()
        .find_map(|l| {
            l.strip_prefix("summary:")
                .or_else(|| l.strip_prefix("totals:"))
        })
        .and_then(|v| v.split_whitespace().next())
        .and_then(|v| v.parse::<u64>().ok())
        .ok_or("no totals in the callgrind output")?;
    if total == 0 {
        return Err("callgrind counted nothing (run_plain not found)".into());
    }
    Ok(total as f64 / marble_rolling::study::steps(k) as f64)
}

/// The hottest functions (self cost) of one configuration's run: `(share %, name)`.
pub fn profile(
    exe: &Path,
    scene: SceneId,
    engine: &str,
    k: u32,
    work: &Path,
    top: usize,
) -> Result<Vec<(f64, String)>, String> {
    let name = Scene::get(scene).name;
    let out = work.join(format!("profile.{name}.{engine}.{k}.out"));
    let status = Command::new("valgrind")
        .arg("--tool=callgrind")
        .arg(format!("--callgrind-out-file={}", out.display()))
        .arg("--toggle-collect=*run_plain*")
        .arg(exe)
        .args(["--callgrind-child", name, engine, &k.to_string()])
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .status()
        .map_err(|e| format!("valgrind: {e}"))?;
    if !status.success() {
        return Err(format!("valgrind exited with {status}"));
    }
    let ann = Command::new("callgrind_annotate")
        .arg("--auto=no")
        .arg(&out)
        .output()
        .map_err(|e| format!("callgrind_annotate: {e}"))?;
    let _ = std::fs::remove_file(&out);
    let text = String::from_utf8_lossy(&ann.stdout);
    let mut rows = Vec::new();
    let mut in_table = false;
    for line in text.lines() {
        if line.contains("file:function") {
            in_table = true;
            continue;
        }
        if !in_table || line.starts_with("---") {
            continue;
        }
        if line.trim().is_empty() {
            if rows.is_empty() {
                continue;
            }
            break;
        }
        let l = line.trim_start();
        let Some(open) = l.find('(') else { continue };
        let Some(close) = l[open..].find("%)") else {
            continue;
        };
        let Ok(pct) = l[open + 1..open + close].trim().parse::<f64>() else {
            continue;
        };
        let rest = l[open + close + 2..].trim();
        let func = rest.split_once(':').map(|(_, f)| f).unwrap_or(rest);
        let func = func.split(" [").next().unwrap_or(func);
        let func = func.split(" (").next().unwrap_or(func);
        // Inlined code is listed under its own source file: sum by function.
        let name = shorten(func);
        match rows
            .iter_mut()
            .find(|(_, n): &&mut (f64, String)| *n == name)
        {
            Some(row) => row.0 += pct,
            None => rows.push((pct, name)),
        }
    }
    if rows.is_empty() {
        return Err("callgrind_annotate gave no table".into());
    }
    rows.sort_by(|a, b| b.0.total_cmp(&a.0));
    rows.truncate(top);
    Ok(rows)
}

/// A function name without generic arguments and crate-internal paths.
fn shorten(f: &str) -> String {
    let mut out = String::new();
    let mut depth = 0;
    for ch in f.chars() {
        match ch {
            '<' => {
                depth += 1;
                if depth == 1 {
                    out.push_str("<…>");
                }
            }
            '>' => depth -= 1,
            _ if depth == 0 => out.push(ch),
            _ => {}
        }
    }
    out.replace("marble_rolling::", "")
}
