//! The `sim` binary's command-line contract (`cargo test --features tools`).

use std::path::PathBuf;
use std::process::{Command, Output};

use serde_json::Value;

fn sim(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_sim"))
        .args(args)
        .output()
        .expect("run sim")
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// Runs `sim --json ...`, checks the exit status is 0 and parses the one line.
fn sim_json(args: &[&str]) -> Value {
    let mut a = args.to_vec();
    a.push("--json");
    let o = sim(&a);
    assert!(o.status.success(), "sim {a:?} failed: {}", stderr(&o));
    let out = String::from_utf8(o.stdout).expect("utf-8");
    assert_eq!(out.lines().count(), 1, "one JSON line: {out}");
    serde_json::from_str(out.trim()).unwrap_or_else(|e| panic!("not JSON ({e}): {out}"))
}

/// A file under this test target's scratch directory. Written under a name
/// of its own and renamed into place: tests run in parallel, and two of them
/// writing the same file in place let one read it half written.
fn scratch(name: &str, content: impl AsRef<[u8]>) -> PathBuf {
    static NEXT: std::sync::atomic::AtomicU32 = std::sync::atomic::AtomicU32::new(0);
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("cli");
    std::fs::create_dir_all(&dir).unwrap();
    let p = dir.join(name);
    let n = NEXT.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    let partial = dir.join(format!("{name}.{}.{n}.partial", std::process::id()));
    std::fs::write(&partial, content).unwrap();
    std::fs::rename(&partial, &p).unwrap();
    p
}

fn s(p: &std::path::Path) -> &str {
    p.to_str().unwrap()
}

/// Tilted so that the marble rolls towards +x' (`ax < 0`).
const RIGHT: &str = "t_s,ax_mg,ay_mg,az_mg\n0,-300,954,0\n";

/// A hole right next to the start, on the right.
const PIT: &str = "name: pit\ntime_limit_s: 5\n---\n#####\n#S.O#\n#.###\n#G..#\n#####\n";

#[test]
fn json_contract_fields_and_types() {
    let v = sim_json(&["--level", "corner", "--autopilot"]);
    assert_eq!(v["outcome"], "won");
    for key in ["steps", "frames", "substeps", "marbles"] {
        assert!(v[key].is_u64(), "{key}: {v}");
    }
    for key in [
        "sim_seconds",
        "dt_s",
        "short_mm",
        "long_mm",
        "marble_radius_mm",
        "speed_x",
        "wall_s",
    ] {
        assert!(v[key].is_number(), "{key}: {v}");
    }
    for key in ["x_mm", "y_mm", "z_mm"] {
        assert!(v["final"][key].is_number(), "final.{key}: {v}");
        assert!(v["start"][key].is_number(), "start.{key}: {v}");
    }
    assert_eq!(v["backend"], "i8f24");
    assert_eq!(v["level"], "corner");
    // Events by default: one step per 1/128 s frame.
    assert_eq!(v["dt_s"].as_f64(), Some(1.0 / 128.0));
    assert_eq!(v["short_mm"].as_f64(), Some(2.0));
    assert_eq!(v["long_mm"].as_f64(), Some(10.0));
    assert_eq!(v["marble_radius_mm"].as_f64(), Some(3.5));
    let steps = v["steps"].as_u64().unwrap();
    assert_eq!(steps, v["frames"].as_u64().unwrap());
    assert!((v["sim_seconds"].as_f64().unwrap() - steps as f64 / 128.0).abs() < 1e-12);
    let hash = v["state_hash"].as_str().expect("hash is a string");
    assert_eq!(hash.len(), 16, "{hash}");
    assert!(
        hash.bytes()
            .all(|b| b.is_ascii_hexdigit() && !b.is_ascii_uppercase()),
        "{hash}"
    );
}

#[test]
fn same_inputs_same_hash() {
    for backend in ["i8f24", "f32", "f64"] {
        let a = sim_json(&["--level", "switchback", "--autopilot", "--backend", backend]);
        let b = sim_json(&["--level", "switchback", "--autopilot", "--backend", backend]);
        assert_eq!(a["state_hash"], b["state_hash"], "{backend}");
        assert_eq!(a["steps"], b["steps"], "{backend}");
        assert_eq!(a["backend"], backend);
    }
}

#[test]
fn human_summary_without_json() {
    let o = sim(&["--level", "first-roll", "--seconds", "0.5"]);
    assert!(o.status.success());
    let out = String::from_utf8(o.stdout).unwrap();
    assert!(out.starts_with("first-roll: timeout"), "{out}");
    assert!(out.contains("state_hash"), "{out}");
}

#[test]
fn seconds_stop_a_run_as_timeout() {
    let v = sim_json(&["--level", "corner", "--seconds", "1"]);
    assert_eq!(v["outcome"], "timeout");
    assert_eq!(v["frames"], 128);
    assert_eq!(v["steps"], 128, "events: a step per frame");
    let f = sim_json(&["--level", "corner", "--seconds", "1", "--stepping", "fixed"]);
    assert_eq!(f["steps"], 1024, "fixed: 8 steps per frame");
    // Flat board: the marble stays put.
    assert_eq!(v["final"], v["start"]);
    // Without --seconds the level's time limit (30 s) ends it.
    let v = sim_json(&["--level", "corner"]);
    assert_eq!(v["outcome"], "timeout");
    assert_eq!(v["sim_seconds"].as_f64(), Some(30.0));
}

#[test]
fn substeps_keep_the_frame_rate() {
    for (n, dt) in [(1u64, 1.0 / 128.0), (4, 1.0 / 512.0), (16, 1.0 / 2048.0)] {
        let v = sim_json(&[
            "--level",
            "corner",
            "--stepping",
            "fixed",
            "--seconds",
            "0.5",
            "--substeps",
            &n.to_string(),
        ]);
        assert_eq!(v["frames"], 64);
        assert_eq!(v["steps"].as_u64(), Some(64 * n));
        assert_eq!(v["dt_s"].as_f64(), Some(dt));
        assert_eq!(v["substeps"].as_u64(), Some(n));
    }
    for bad in ["3", "0", "32", "x"] {
        let o = sim(&["--level", "corner", "--substeps", bad]);
        assert!(!o.status.success(), "{bad}");
        assert!(stderr(&o).contains("--substeps"), "{}", stderr(&o));
    }
}

#[test]
fn check_reports_line_and_column() {
    let bad = scratch(
        "bad.level",
        "name: bad\ntime_limit_s: 10\n---\n#####\n#S.G#\n##x##\n",
    );
    let o = sim(&["--check", s(&bad)]);
    assert!(!o.status.success());
    let err = stderr(&o);
    assert!(err.contains(&format!("{}:6:3: ", s(&bad))), "{err}");
    assert!(err.contains("unknown tile"), "{err}");

    let o = sim(&["--check", s(&scratch("pit.level", PIT))]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert_eq!(String::from_utf8_lossy(&o.stdout).trim(), "ok");

    // The same error when the bad level is simulated.
    let o = sim(&["--level", s(&bad)]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains(":6:3: "), "{}", stderr(&o));
}

#[test]
fn unknown_backend_and_level_fail_with_a_message() {
    let o = sim(&["--level", "corner", "--backend", "q15"]);
    assert_eq!(o.status.code(), Some(2));
    let err = stderr(&o);
    assert!(
        err.contains("unknown backend `q15`") && err.contains("f32-micromath"),
        "{err}"
    );

    let o = sim(&["--level", "no-such-level"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("no-such-level"), "{}", stderr(&o));
}

#[test]
fn bad_tilt_trace_names_the_line() {
    let t = scratch(
        "bad-trace.csv",
        "t_s,ax_mg,ay_mg,az_mg\n0,0,1000,0\n\n0.5,-100,abc,0\n",
    );
    let o = sim(&["--level", "corner", "--tilt-trace", s(&t)]);
    assert_eq!(o.status.code(), Some(2));
    let err = stderr(&o);
    assert!(
        err.contains(&format!("{}:4: ", s(&t))) && err.contains("ay_mg"),
        "{err}"
    );

    let t = scratch("bad-header.csv", "time,x,y,z\n0,0,1000,0\n");
    let o = sim(&["--level", "corner", "--tilt-trace", s(&t)]);
    assert_eq!(o.status.code(), Some(2));
    assert!(
        stderr(&o).contains(":1: expected the header"),
        "{}",
        stderr(&o)
    );

    let t = scratch(
        "backwards.csv",
        "t_s,ax_mg,ay_mg,az_mg\n1,0,1000,0\n0.5,0,1000,0\n",
    );
    let o = sim(&["--level", "corner", "--tilt-trace", s(&t)]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains(":3: "), "{}", stderr(&o));
}

#[test]
fn tilt_right_rolls_towards_plus_x() {
    let t = scratch("right.csv", RIGHT);
    let v = sim_json(&[
        "--level",
        "first-roll",
        "--tilt-trace",
        s(&t),
        "--seconds",
        "0.1",
    ]);
    let (x0, x1) = (
        v["start"]["x_mm"].as_f64().unwrap(),
        v["final"]["x_mm"].as_f64().unwrap(),
    );
    assert!(x1 > x0 + 1.0, "x {x0} → {x1}");
    assert_eq!(v["start"]["z_mm"], v["final"]["z_mm"]);
    // Held long enough, the marble reaches the goal at the right end.
    let v = sim_json(&["--level", "first-roll", "--tilt-trace", s(&t)]);
    assert_eq!(v["outcome"], "won");

    // The other way round it stays against the left wall.
    let t = scratch("left.csv", "t_s,ax_mg,ay_mg,az_mg\n0,300,954,0\n");
    let v = sim_json(&[
        "--level",
        "first-roll",
        "--tilt-trace",
        s(&t),
        "--seconds",
        "0.5",
    ]);
    assert!(v["final"]["x_mm"].as_f64().unwrap() <= v["start"]["x_mm"].as_f64().unwrap());
}

#[test]
fn trace_has_one_row_per_physics_step() {
    let tilt = scratch("right-trace.csv", RIGHT);
    let out = PathBuf::from(env!("CARGO_TARGET_TMPDIR"))
        .join("cli")
        .join("steps.csv");
    for substeps in ["8", "2"] {
        let plain = sim_json(&[
            "--stepping",
            "fixed",
            "--level",
            "first-roll",
            "--tilt-trace",
            s(&tilt),
            "--substeps",
            substeps,
        ]);
        let v = sim_json(&[
            "--stepping",
            "fixed",
            "--level",
            "first-roll",
            "--tilt-trace",
            s(&tilt),
            "--substeps",
            substeps,
            "--trace",
            s(&out),
        ]);
        // Tracing does not change the run.
        assert_eq!(v["state_hash"], plain["state_hash"]);
        let text = std::fs::read_to_string(&out).unwrap();
        let mut lines = text.lines();
        assert_eq!(
            lines.next(),
            Some("step,t_s,x_mm,y_mm,z_mm,vx_mm_s,vy_mm_s,vz_mm_s")
        );
        let rows: Vec<Vec<f64>> = lines
            .map(|l| l.split(',').map(|f| f.parse::<f64>().expect(l)).collect())
            .collect();
        let steps = v["steps"].as_u64().unwrap();
        assert_eq!(rows.len() as u64, steps);
        let dt = v["dt_s"].as_f64().unwrap();
        for (n, r) in rows.iter().enumerate() {
            assert_eq!(r.len(), 8);
            assert_eq!(r[0], (n + 1) as f64);
            assert!((r[1] - (n + 1) as f64 * dt).abs() < 1e-9);
        }
        let last = rows.last().unwrap();
        for (i, key) in ["x_mm", "y_mm", "z_mm"].iter().enumerate() {
            let end = v["final"][key].as_f64().unwrap();
            assert!(
                (last[2 + i] - end).abs() < 1e-5,
                "{key}: {} vs {end}",
                last[2 + i]
            );
        }
        // Moving right: x grows, vx positive.
        assert!(last[2] > rows[0][2] && last[5] > 0.0);
    }
}

/// With a tilt that changes from frame to frame (the autopilot), sleeping
/// marbles are woken by each new pull: the per-step replay must agree with the
/// frames it traces all the same (it once reported a divergence here).
#[test]
fn trace_follows_a_changing_tilt() {
    let out = PathBuf::from(env!("CARGO_TARGET_TMPDIR"))
        .join("cli")
        .join("autopilot-steps.csv");
    let fixed = ["--level", "corner", "--autopilot", "--stepping", "fixed"];
    let plain = sim_json(&fixed);
    let v = sim_json(&[&fixed[..], &["--trace", s(&out)]].concat());
    assert_eq!(v["outcome"], "won");
    assert_eq!(v["state_hash"], plain["state_hash"]);
    let rows = std::fs::read_to_string(&out).unwrap().lines().count() as u64;
    assert_eq!(
        rows,
        v["steps"].as_u64().unwrap() + 1,
        "a header and a row per step"
    );
    // Event steps: the replay of each frame's flights agrees with the frame too
    // (a changing tilt, board motion), with 8 rows per 1/128 s step.
    for level in ["corner", "rocking-board"] {
        let args = ["--level", level, "--autopilot", "--stepping", "events"];
        let plain = sim_json(&args);
        let mut traced = args.to_vec();
        traced.extend(["--trace", s(&out)]);
        let v = sim_json(&traced);
        assert_eq!(v["outcome"], "won", "{level}");
        assert_eq!(v["state_hash"], plain["state_hash"], "{level}");
        let rows = std::fs::read_to_string(&out).unwrap().lines().count() as u64;
        assert_eq!(rows, 8 * v["steps"].as_u64().unwrap() + 1, "{level}");
    }
}

/// Rolls the two marbles of `two-marbles` into each other (along z'), apart, and
/// along x' (each held 0.5 s).
const KNOCK: &str =
    "t_s,ax_mg,ay_mg,az_mg\n0,0,954,-300\n0.5,0,954,300\n1,-300,908,300\n1.5,300,908,-300\n";

/// Events by default, one step per 1/128 s frame; `fixed` on request; bad modes
/// fail.
#[test]
fn event_stepping_is_a_step_per_frame() {
    let v = sim_json(&["--level", "corner", "--autopilot"]);
    assert_eq!(v["outcome"], "won");
    assert_eq!(v["stepping"], "events");
    assert_eq!(v["substeps"], 1);
    assert_eq!(v["steps"], v["frames"]);
    assert_eq!(v["dt_s"].as_f64(), Some(1.0 / 128.0));
    let e = sim_json(&["--level", "corner", "--autopilot", "--stepping", "events"]);
    assert_eq!(e["state_hash"], v["state_hash"], "the default is events");
    let f = sim_json(&["--level", "corner", "--autopilot", "--stepping", "fixed"]);
    assert_eq!(f["stepping"], "fixed");
    assert_eq!(f["substeps"], 8);
    // Events at 1024 steps/s are allowed too (2^7 ..= 2^10 steps/s).
    let v8 = sim_json(&[
        "--level",
        "corner",
        "--stepping",
        "events",
        "--substeps",
        "8",
        "--seconds",
        "0.5",
    ]);
    assert_eq!(v8["dt_s"].as_f64(), Some(1.0 / 1024.0));
    let o = sim(&["--level", "corner", "--stepping", "exact"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("fixed, events"), "{}", stderr(&o));
}

/// The trace has a row per 1/1024 s in both modes with every marble in it, ends
/// at the JSON's final state, and the two marbles never overlap in any row.
#[test]
fn trace_has_every_marble_every_millisecond_in_both_modes() {
    let tilt = scratch("knock.csv", KNOCK);
    for stepping in ["fixed", "events"] {
        let out = PathBuf::from(env!("CARGO_TARGET_TMPDIR"))
            .join("cli")
            .join(format!("two-marbles-{stepping}.csv"));
        let args = [
            "--level",
            "two-marbles",
            "--tilt-trace",
            s(&tilt),
            "--seconds",
            "2",
            "--stepping",
            stepping,
        ];
        let plain = sim_json(&args);
        let mut traced = args.to_vec();
        traced.extend(["--trace", s(&out)]);
        let v = sim_json(&traced);
        assert_eq!(v["state_hash"], plain["state_hash"], "{stepping}");
        assert_eq!(v["stepping"], stepping);
        assert_eq!(v["marbles"], 2);
        let finals = v["final"]["marbles"].as_array().expect("final.marbles");
        assert_eq!(finals.len(), 2, "{v}");
        assert_eq!(v["final"]["x_mm"], finals[0]["x_mm"], "marble 0 at the top");
        assert_eq!(v["start"]["marbles"].as_array().map(Vec::len), Some(2));

        let text = std::fs::read_to_string(&out).unwrap();
        let mut lines = text.lines();
        assert_eq!(
            lines.next(),
            Some(
                "step,t_s,x_mm,y_mm,z_mm,vx_mm_s,vy_mm_s,vz_mm_s,\
                 x1_mm,y1_mm,z1_mm,vx1_mm_s,vy1_mm_s,vz1_mm_s"
            )
        );
        let rows: Vec<Vec<f64>> = lines
            .map(|l| l.split(',').map(|f| f.parse::<f64>().expect(l)).collect())
            .collect();
        let seconds = v["sim_seconds"].as_f64().unwrap();
        assert!(seconds >= 1.0, "{stepping}: {v}");
        assert!(
            rows.len() as f64 >= 1024.0 * seconds,
            "{stepping}: {} rows in {seconds} s",
            rows.len()
        );
        // A row every 1/1024 s, in time order, every marble in it.
        for (n, r) in rows.iter().enumerate() {
            assert_eq!(r.len(), 2 + 6 * 2, "{stepping} row {n}");
            assert!(
                (r[1] - (n + 1) as f64 / 1024.0).abs() < 1e-9,
                "{stepping} row {n}: t {}",
                r[1]
            );
        }
        // The last row is the final state of every marble.
        let last = rows.last().unwrap();
        let keys = ["x_mm", "y_mm", "z_mm", "vx_mm_s", "vy_mm_s", "vz_mm_s"];
        for (m, fin) in finals.iter().enumerate() {
            for (i, key) in keys.iter().enumerate() {
                let end = fin[key].as_f64().unwrap();
                let got = last[2 + 6 * m + i];
                assert!(
                    (got - end).abs() < 1e-5,
                    "{stepping} marble {m} {key}: {got} vs {end}"
                );
            }
        }
        // Never closer than two radii less a hair, and they met. Fixed steps
        // separate a pair at the step's end (an impact at 0.3 g overlaps by
        // 16 µm for that step); event steps stop at the touch (a few µm, the
        // slices' push-out).
        let tol = if stepping == "fixed" { 0.02 } else { 0.005 };
        let two_r = 2.0 * v["marble_radius_mm"].as_f64().unwrap();
        let closest = rows
            .iter()
            .map(|r| {
                ((r[2] - r[8]).powi(2) + (r[3] - r[9]).powi(2) + (r[4] - r[10]).powi(2)).sqrt()
            })
            .fold(f64::INFINITY, f64::min);
        assert!(
            closest >= two_r - tol,
            "{stepping}: {closest} mm apart (2r = {two_r})"
        );
        assert!(
            closest < two_r + 0.1,
            "{stepping}: the marbles never met ({closest} mm)"
        );
    }
}

#[test]
fn falling_into_a_hole_exits_zero() {
    let level = scratch("pit.level", PIT);
    let tilt = scratch("pit-right.csv", RIGHT);
    let v = sim_json(&["--level", s(&level), "--tilt-trace", s(&tilt)]);
    assert_eq!(v["outcome"], "fell");
    assert_eq!(v["level"], "pit");
    assert!(v["final"]["y_mm"].as_f64().unwrap() < 0.0, "{v}");
}

#[test]
fn gif_is_written_and_small() {
    let out = PathBuf::from(env!("CARGO_TARGET_TMPDIR"))
        .join("cli")
        .join("corner.gif");
    let o = sim(&["--level", "corner", "--autopilot", "--gif", s(&out)]);
    assert!(o.status.success(), "{}", stderr(&o));
    let bytes = std::fs::read(&out).unwrap();
    assert!(bytes.starts_with(b"GIF89a"), "GIF header");
    assert!(bytes.len() < 1 << 20, "{} bytes", bytes.len());
    // 9×5 tiles at 12 px each.
    assert_eq!(u16::from_le_bytes([bytes[6], bytes[7]]), 9 * 12);
    assert_eq!(u16::from_le_bytes([bytes[8], bytes[9]]), 5 * 12);
}

#[test]
fn play_needs_a_terminal() {
    let o = Command::new(env!("CARGO_BIN_EXE_play"))
        .args(["--level", "corner"])
        .stdin(std::process::Stdio::null())
        .output()
        .expect("run play");
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("must be a terminal"), "{}", stderr(&o));
}

#[test]
fn check_names_the_value_that_setup_would_refuse() {
    // (file, content, line:column, words): issue 12 item 4.1 and 4.2.
    let cases = [
        (
            "tiny-pitch.level",
            "short_mm: 0.001\nlong_mm: 0.003\nmarble_radius_mm: 0.001\n---\n#####\n#S.G#\n#####\n",
            "2:10",
            [
                "cell pitch short_mm + long_mm must be 1 ..= 100 mm",
                "0.004 mm",
            ],
        ),
        (
            "long-pitch.level",
            "short_mm: 50\nlong_mm: 50.001\nmarble_radius_mm: 25\n---\n#####\n#S.G#\n#####\n",
            "2:10",
            [
                "cell pitch short_mm + long_mm must be 1 ..= 100 mm",
                "50 + 50.001 = 100.001 mm",
            ],
        ),
    ];
    for (name, content, at, words) in cases {
        let p = scratch(name, content);
        let o = sim(&["--check", s(&p)]);
        assert_eq!(o.status.code(), Some(1), "{name}");
        let err = stderr(&o);
        assert!(err.starts_with(&format!("{}:{at}: ", s(&p))), "{err}");
        for w in words {
            assert!(err.contains(w), "{err:?} lacks {w:?}");
        }
        assert!(!err.contains("marble does not fit"), "{err}");
        // Simulating it gives the same place and words, not a debug value.
        let o = sim(&["--level", s(&p)]);
        assert_eq!(o.status.code(), Some(2), "{name}");
        let err = stderr(&o);
        assert!(
            err.contains(&format!("{}:{at}: cell pitch", s(&p))),
            "{err}"
        );
        assert!(
            !err.contains("Layout") && !err.contains("cannot be set up"),
            "{err}"
        );
    }
}

#[test]
fn a_byte_order_mark_is_fine_in_levels_and_tilt_traces() {
    const BOM: &str = "\u{feff}";
    let level = "name: bom\ntime_limit_s: 5\n---\n#######\n#S...G#\n#######\n";
    let plain = scratch("plain.level", level);
    let marked = scratch("bom.level", format!("{BOM}{level}"));
    assert_eq!(std::fs::read(&marked).unwrap()[..3], [0xEF, 0xBB, 0xBF]);
    let o = sim(&["--check", s(&marked)]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert_eq!(String::from_utf8_lossy(&o.stdout).trim(), "ok");

    let trace_plain = scratch("plain-right.csv", RIGHT);
    let trace_marked = scratch("bom-right.csv", format!("{BOM}{RIGHT}"));
    let run =
        |lvl: &PathBuf, trace: &PathBuf| sim_json(&["--level", s(lvl), "--tilt-trace", s(trace)]);
    let reference = run(&plain, &trace_plain);
    assert_eq!(reference["level"], "bom");
    assert_eq!(reference["outcome"], "won");
    for (lvl, trace) in [
        (&marked, &trace_plain),
        (&plain, &trace_marked),
        (&marked, &trace_marked),
    ] {
        let v = run(lvl, trace);
        for key in ["level", "outcome", "steps", "state_hash"] {
            assert_eq!(v[key], reference[key], "{key} with {lvl:?}, {trace:?}");
        }
    }
}

/// `--help` says what a run steps by when nobody asks.
#[test]
fn help_names_events_as_the_default_stepping() {
    let o = sim(&["--help"]);
    let out = String::from_utf8_lossy(&o.stdout);
    let stepping: String = out
        .lines()
        .skip_while(|l| !l.contains("--stepping"))
        .take_while(|l| !l.trim_start().starts_with("--trace"))
        .collect();
    assert!(stepping.contains("[default: events]"), "{out}");
}

#[test]
fn a_generated_maze_prints_checks_and_is_won() {
    let print = |storeys: &str| {
        let o = sim(&["--generate", "11", "--storeys", storeys, "--print-level"]);
        assert!(o.status.success(), "{}", stderr(&o));
        String::from_utf8(o.stdout).unwrap()
    };
    for storeys in ["1", "3"] {
        let text = print(storeys);
        assert_eq!(text, print(storeys), "the same text every time");
        assert!(
            text.starts_with(&format!("name: maze-11-6x6x{storeys}-d2\n")),
            "{text}"
        );
        let file = scratch(&format!("maze-11-{storeys}.level"), &text);
        let o = sim(&["--check", s(&file)]);
        assert!(o.status.success(), "{}", stderr(&o));
        assert_eq!(String::from_utf8_lossy(&o.stdout).trim(), "ok");
        for stepping in ["events", "fixed"] {
            let from_file = sim_json(&["--level", s(&file), "--autopilot", "--stepping", stepping]);
            assert_eq!(from_file["outcome"], "won", "{stepping}\n{text}");
            // Played straight from the seed: the same level, the same run.
            let direct = sim_json(&[
                "--generate",
                "11",
                "--storeys",
                storeys,
                "--autopilot",
                "--stepping",
                stepping,
            ]);
            assert_eq!(direct["state_hash"], from_file["state_hash"], "{stepping}");
            assert_eq!(direct["frames"], from_file["frames"], "{stepping}");
        }
    }
}

#[test]
fn generate_options_are_checked() {
    let cases: [(&[&str], &str); 4] = [
        (&["--generate", "1", "--size", "16"], "--size"),
        (&["--generate", "1", "--storeys", "5"], "--storeys"),
        (&["--generate", "1", "--level", "corner"], "--level"),
        (&["--level", "corner", "--size", "4"], "need --generate"),
    ];
    for (args, words) in cases {
        let o = sim(args);
        assert_eq!(o.status.code(), Some(2), "{args:?}");
        assert!(stderr(&o).contains(words), "{args:?}: {}", stderr(&o));
    }
}

/// `cargo play`'s binary: its argument errors come before it needs a terminal.
fn play(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_play"))
        .args(args)
        .output()
        .expect("run play")
}

/// A seed that is not a `u32` (negative, not a number, 23 digits) is refused
/// by both tools with the range, as every ranged option is.
#[test]
fn a_bad_seed_names_the_seed_range() {
    let too_long = "1".repeat(23);
    for seed in ["-1", "abc", too_long.as_str(), "4294967296", "1.5", ""] {
        for (tool, o) in [
            ("sim", sim(&["--generate", seed, "--autopilot"])),
            ("play", play(&["--generate", seed])),
        ] {
            let err = stderr(&o);
            assert_eq!(
                o.status.code(),
                Some(2),
                "{tool} --generate {seed:?}: {err}"
            );
            assert!(
                err.contains("0..=4294967295") && err.contains("--generate"),
                "{tool} --generate {seed:?}: {err}"
            );
            for old in ["unexpected argument", "invalid digit", "number too large"] {
                assert!(!err.contains(old), "{tool} --generate {seed:?}: {err}");
            }
        }
    }
    // The ends of the range are seeds.
    for seed in ["0", "4294967295"] {
        let o = sim(&["--generate", seed, "--size", "3", "--print-level"]);
        assert!(o.status.success(), "--generate {seed}: {}", stderr(&o));
        let text = String::from_utf8_lossy(&o.stdout).into_owned();
        assert!(text.starts_with(&format!("name: maze-{seed}-")), "{text}");
    }
}

/// `--print-level` prints a generated maze: without `--generate` it says so
/// (and asks for nothing else), with a `--level` instead it is refused, not
/// a silent success.
#[test]
fn print_level_needs_generate() {
    for args in [
        &["--print-level"][..],
        &["--level", "corner", "--print-level"],
        &["--print-level", "--autopilot"],
    ] {
        let o = sim(args);
        let err = stderr(&o);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {err}");
        assert!(o.stdout.is_empty(), "{args:?}: printed something");
        assert!(
            err.contains("--print-level needs --generate SEED"),
            "{args:?}: {err}"
        );
        assert!(
            !err.contains("--level <"),
            "{args:?} asks for --level: {err}"
        );
    }
}

/// A level whose fourth line has a byte that is not UTF-8 (0xFF) at column 3.
const NOT_UTF8_LEVEL: &[u8] = b"name: latin\ntime_limit_s: 5\n---\n#S\xffG#\n#####\n";

#[test]
fn a_level_that_is_not_utf8_is_refused_at_its_line_and_column() {
    let p = scratch("latin.level", NOT_UTF8_LEVEL);
    let want = format!("{}:4:3: not UTF-8 (byte 0xFF)", s(&p));
    let o = sim(&["--check", s(&p)]);
    assert_eq!(o.status.code(), Some(2));
    assert_eq!(stderr(&o), format!("{want}\n"));
    let o = sim(&["--level", s(&p)]);
    assert_eq!(o.status.code(), Some(2));
    let err = stderr(&o);
    assert_eq!(err, format!("sim: error: {want}\n"));
    // The file exists and was read: not "neither a built-in level nor a readable file".
    assert!(!err.contains("readable"), "{err}");
    // After a byte-order mark, columns count from the first character after it;
    // a character cut short by the end of the file is reported at its first byte.
    let p = scratch("cut.level", b"\xef\xbb\xbfname: caf\xc3\xa9\n---\n\xe2\x82");
    let o = sim(&["--check", s(&p)]);
    assert_eq!(o.status.code(), Some(2));
    assert_eq!(
        stderr(&o),
        format!("{}:3:1: not UTF-8 (byte 0xE2)\n", s(&p))
    );
}

#[test]
fn a_tilt_trace_that_is_not_utf8_is_refused_at_its_line() {
    let t = scratch(
        "latin.csv",
        b"t_s,ax_mg,ay_mg,az_mg\n0,0,1000,0\n0.5,\xb5100,1000,0\n",
    );
    let o = sim(&["--level", "corner", "--tilt-trace", s(&t)]);
    assert_eq!(o.status.code(), Some(2));
    assert_eq!(
        stderr(&o),
        format!(
            "sim: error: tilt trace {}:3: not UTF-8 (byte 0xB5, column 5)\n",
            s(&t)
        )
    );
}

/// `err` quotes at most 60 characters of the offending text `filler` (a run of
/// one character), cut with an ellipsis, and stays short.
fn quotes_at_most_60(err: &str, filler: char) {
    let longest = err
        .split(|c| c != filler)
        .map(|run| run.chars().count())
        .max()
        .unwrap_or(0);
    assert!(
        (1..=60).contains(&longest),
        "a run of {longest} × {filler:?}: {err}"
    );
    assert!(err.contains('…'), "no ellipsis: {err}");
    assert!(err.len() < 1000, "{} bytes: {}…", err.len(), &err[..300]);
}

#[test]
fn error_lines_quote_at_most_60_characters() {
    let digits = "9".repeat(100_000);
    // Finite as an f64 (1e300): a number, out of range or out of order.
    let big = "9".repeat(300);
    // Tilt traces: a huge number, a huge header, a huge negative time, a huge
    // reading and a huge time earlier than the one before.
    let cases = [
        (
            format!("t_s,ax_mg,ay_mg,az_mg\n0,{digits}x,1000,0\n"),
            "ax_mg: `999",
        ),
        (format!("t_s,{digits}\n"), "expected the header"),
        (
            format!("t_s,ax_mg,ay_mg,az_mg\n-{digits},0,1000,0\n"),
            "t_s: `-999",
        ),
        (
            format!("t_s,ax_mg,ay_mg,az_mg\n0,0,{big},0\n"),
            "beyond ±16000 mg",
        ),
        (
            format!("t_s,ax_mg,ay_mg,az_mg\n1{big},0,1000,0\n{big},0,1000,0\n"),
            "earlier than",
        ),
    ];
    for (n, (trace, words)) in cases.iter().enumerate() {
        let t = scratch(&format!("huge-{n}.csv"), trace);
        let o = sim(&["--level", "corner", "--tilt-trace", s(&t)]);
        assert_eq!(o.status.code(), Some(2), "{words}");
        let err = stderr(&o);
        assert!(err.contains(words), "{words}: {err}");
        quotes_at_most_60(&err, '9');
    }
    // Levels quote nothing but their line and column: a huge value, key or row
    // is one short line.
    for (n, level) in [
        format!("time_limit_s: {digits}\n---\n#####\n#S.G#\n#####\n"),
        format!("{digits}: 1\n---\n#####\n#S.G#\n#####\n"),
        format!("---\n{digits}\n"),
    ]
    .iter()
    .enumerate()
    {
        let p = scratch(&format!("huge-{n}.level"), level);
        let o = sim(&["--check", s(&p)]);
        assert_eq!(o.status.code(), Some(1));
        let err = stderr(&o);
        assert!(err.len() < 300 && err.lines().count() == 1, "{err}");
    }
    // Arguments: ours and clap's.
    let x = "x".repeat(100_000);
    for args in [
        vec!["--level", "corner", "--backend", &x],
        vec!["--level", &x],
        vec!["--level", "corner", "--seconds", &x],
        vec!["--level", "corner", "--substeps", &x],
        vec!["--level", "corner", "--stepping", &x],
        vec!["--level", "corner", &x],
    ] {
        let o = sim(&args);
        assert_eq!(o.status.code(), Some(2), "{:?}", &args[..args.len() - 1]);
        quotes_at_most_60(&stderr(&o), 'x');
    }
}

#[test]
fn out_of_range_names_the_range() {
    let p = scratch(
        "bouncy.level",
        "name: bouncy\nrestitution: 1.5\n---\n#####\n#S.G#\n#####\n",
    );
    let want = format!("{}:2:14: value out of range: restitution is 0 ..= 1", s(&p));
    let o = sim(&["--check", s(&p)]);
    assert_eq!(o.status.code(), Some(1));
    assert_eq!(stderr(&o), format!("{want}\n"));
    let o = sim(&["--level", s(&p)]);
    assert_eq!(o.status.code(), Some(2));
    assert_eq!(stderr(&o), format!("sim: error: {want}\n"));
}

/// A negative value is refused with the key's range, at the sign, by
/// `--check` (the page's editor shows the same words after the line and column).
#[test]
fn a_negative_value_names_the_range() {
    let p = scratch(
        "negative.level",
        "name: negative\ntime_limit_s: -1\n---\n#####\n#S.G#\n#####\n",
    );
    let o = sim(&["--check", s(&p)]);
    assert_eq!(o.status.code(), Some(1));
    assert_eq!(
        stderr(&o),
        format!(
            "{}:2:15: value out of range: time_limit_s is 1 ..= 3600\n",
            s(&p)
        )
    );
}

/// `effects: none` slides 7/5 as far as `effects: rolling` in the same time
/// under the same tilt (a marble that rolls turns 2/7 of the pull into spin).
/// With events: fixed steps cap the speed at r/4 per step (875 mm/s at 1024
/// steps/s), which a 0.3 g slide passes within the half second.
#[test]
fn the_effects_list_is_the_physics_from_the_command_line() {
    let wall = "#".repeat(127);
    let level = |effects: &str| {
        format!(
            "name: slide\n{effects}time_limit_s: 60\n---\n{wall}\n#S{}G#\n{wall}\n",
            ".".repeat(123)
        )
    };
    let trace = scratch("slide-right.csv", RIGHT);
    let run = |name: &str, effects: &str| {
        let p = scratch(name, level(effects));
        let v = sim_json(&[
            "--level",
            s(&p),
            "--tilt-trace",
            s(&trace),
            "--seconds",
            "0.5",
            "--stepping",
            "events",
        ]);
        assert_eq!(v["outcome"], "timeout", "{effects:?}: {v}");
        v["final"]["x_mm"].as_f64().unwrap() - v["start"]["x_mm"].as_f64().unwrap()
    };
    let sliding = run("slide-none.level", "effects: none\n");
    let empty = run("slide-empty.level", "effects:\n");
    let rolling = run("slide-rolling.level", "effects: rolling\n");
    let default = run("slide-default.level", "");
    println!("0.5 s: sliding {sliding:.3} mm, rolling {rolling:.3} mm");
    assert_eq!(sliding, empty);
    assert_eq!(rolling, default);
    assert!(rolling > 50.0, "{rolling} mm");
    let ratio = sliding / rolling;
    assert!((ratio - 1.4).abs() < 0.01, "sliding/rolling = {ratio}");
}
