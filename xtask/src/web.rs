//! `cargo web`: the game in a browser. Builds `marble-web` (web/) for
//! `wasm32-unknown-unknown` — adding the target with rustup on first use, as
//! `cargo qemu` adds the thumb ones — and serves web/www with the module on
//! 127.0.0.1 from a small std-only HTTP server: no CDN, no bundler. The
//! server sends the module and the page gzipped to a browser that takes it
//! (`flate2`, the crate the workspace already builds). `cargo xtask web-test` runs the browser test (web/test) against the
//! same server in Debian's Chromium, installing Chromium and Node.js with
//! apt-get when it can (root) and the test's npm packages with `npm ci`.
//! `GET /race?…` is the race's relay between pages ([`crate::race_relay`]).

use std::io::{BufRead, BufReader, Read, Write};

use flate2::write::GzEncoder;
use flate2::Compression;
use std::net::{Ipv4Addr, TcpListener, TcpStream};
use std::path::{Component, Path, PathBuf};
use std::process::{Command, Stdio};
use std::thread;
use std::time::Duration;

use crate::error::{say, Failure, Outcome};
use crate::hex_files;
use crate::process;
use crate::race_relay;
use crate::setup;
use crate::workspace;

/// The browser's target.
pub const WASM: &str = "wasm32-unknown-unknown";
/// The port `cargo web` serves on unless told otherwise.
pub const DEFAULT_PORT: u16 = 8128;
/// The module's name in the page (web/www/app.js fetches it).
const WASM_URL: &str = "/marble_web.wasm";
/// The universal hex in the page (web/www/app.js fetches it for the download).
const HEX_URL: &str = "/marble-rolling.hex";
/// The largest request head read; the page only ever sends short GETs.
const MAX_HEAD: usize = 16 * 1024;

/// `cargo web [--port N] [--no-serve]`.
pub fn run(port: u16, no_serve: bool) -> Outcome {
    let wasm = build()?;
    if no_serve {
        return Ok(0);
    }
    let hex = universal_hex()?;
    if hex.is_file() {
        say!(
            "the editor's Download for micro:bit starts from {}",
            hex.display()
        );
    } else {
        say!(
            "no {}: run `cargo xtask hex` for the editor's Download for micro:bit",
            hex.display()
        );
    }
    let (listener, url) = bind(port)?;
    // On stdout, flushed: the browser test (run on its own) reads the URL from it.
    println!("serving {url} (Ctrl-C stops)");
    let _ = std::io::stdout().flush();
    serve(listener, www(), wasm, hex);
}

/// Where `cargo xtask hex` writes the universal hex.
fn universal_hex() -> Result<PathBuf, Failure> {
    Ok(workspace::target_dir()?
        .join("hex")
        .join(hex_files::UNIVERSAL))
}

/// `cargo xtask web-test [--screenshot FILE]`: builds, serves on a free port
/// and runs web/test/browser.test.mjs against it; its exit status is ours.
pub fn test(screenshot: Option<PathBuf>) -> Outcome {
    let wasm = build()?;
    let hex = universal_hex()?;
    if hex.is_file() {
        say!("the download starts from {} as it is", hex.display());
    } else {
        // The download's test needs it; CI has built it by now.
        hex_files::run(&[])?;
    }
    let chromium = setup::apt_tool("chromium", "chromium")?;
    let node = setup::apt_tool("node", "nodejs")?;
    let npm = setup::apt_tool("npm", "npm")?;
    let dir = workspace::root().join("web/test");
    let installed = ["playwright-core", "@microbit/microbit-universal-hex"]
        .iter()
        .all(|package| dir.join("node_modules").join(package).is_dir());
    if !installed {
        let mut ci = Command::new(npm);
        ci.current_dir(&dir).args(["ci", "--no-audit", "--no-fund"]);
        process::quietly(
            "installing the browser test's npm packages (npm ci)…",
            &mut [ci],
        )?;
    }
    let (listener, url) = bind(0)?;
    let www = www();
    thread::spawn(move || serve(listener, www, wasm, hex));
    say!("serving {url} for the browser test");
    let mut node = Command::new(node);
    node.current_dir(&dir)
        .arg("browser.test.mjs")
        .env("MARBLE_WEB_URL", &url)
        .env("CHROMIUM", chromium)
        .env("MARBLE_ROOT", workspace::root());
    if let Some(path) = screenshot {
        let path = std::env::current_dir().map_or(path.clone(), |cwd| cwd.join(path));
        node.env("MARBLE_WEB_SCREENSHOT", path);
    }
    let status = process::status(&mut node)?;
    Ok(process::code(status))
}

/// web/www: the page, served as it is.
fn www() -> PathBuf {
    workspace::root().join("web/www")
}

/// Builds the module (profile `web`: release without debug info and symbols,
/// see the root Cargo.toml), prints its path and size, and returns the path.
pub fn build() -> Result<PathBuf, Failure> {
    setup::target(WASM)?;
    let mut cmd = workspace::cargo();
    cmd.args([
        "build",
        "--profile",
        "web",
        "-p",
        "marble-web",
        "--target",
        WASM,
        "--message-format=json-render-diagnostics",
    ]);
    let shown = process::shown(&cmd);
    say!("building marble-web for {WASM}");
    cmd.stdin(Stdio::null()).stdout(Stdio::piped());
    let mut child = process::spawn(&mut cmd)?;
    let mut wasm = None;
    if let Some(stdout) = child.stdout.take() {
        for line in BufReader::new(stdout).lines() {
            let Ok(line) = line else { break };
            if let Some(path) = wasm_of(&line) {
                wasm = Some(path);
            }
        }
    }
    let status = child
        .wait()
        .map_err(|e| Failure::new(format!("waiting for `{shown}`: {e}")))?;
    if !status.success() {
        return Err(Failure::new(format!(
            "building marble-web failed: `{shown}` exited with {}",
            process::code(status)
        ))
        .status(process::code(status).max(1)));
    }
    let wasm = wasm
        .ok_or_else(|| Failure::new(format!("`{shown}` succeeded but reported no .wasm file")))?;
    let size = std::fs::metadata(&wasm)
        .map_err(|e| Failure::new(format!("cannot read {}: {e}", wasm.display())))?
        .len();
    let bytes = std::fs::read(&wasm)
        .map_err(|e| Failure::new(format!("cannot read {}: {e}", wasm.display())))?;
    println!(
        "{}: {size} bytes, {} gzipped (as served)",
        wasm.display(),
        gzip(&bytes).len()
    );
    Ok(wasm)
}

/// The .wasm file named in one of cargo's JSON messages, if it is marble-web's.
fn wasm_of(line: &str) -> Option<PathBuf> {
    let message: serde_json::Value = serde_json::from_str(line).ok()?;
    if message["reason"] != "compiler-artifact" || message["target"]["name"] != "marble_web" {
        return None;
    }
    message["filenames"]
        .as_array()?
        .iter()
        .filter_map(|f| f.as_str())
        .find(|f| f.ends_with(".wasm"))
        .map(PathBuf::from)
}

/// A listener on 127.0.0.1:`port` (0: any free port) and its URL.
fn bind(port: u16) -> Result<(TcpListener, String), Failure> {
    let listener = TcpListener::bind((Ipv4Addr::LOCALHOST, port)).map_err(|e| {
        Failure::new(format!(
            "cannot listen on 127.0.0.1:{port}: {e} (choose another with --port, 0 for any free one)"
        ))
    })?;
    let port = listener
        .local_addr()
        .map_err(|e| Failure::new(format!("cannot read the listening address: {e}")))?
        .port();
    Ok((listener, format!("http://127.0.0.1:{port}/")))
}

/// Serves until the process ends, a thread per connection (a browser opens a
/// few at once, and one slow client must not hold up the page).
fn serve(listener: TcpListener, www: PathBuf, wasm: PathBuf, hex: PathBuf) -> ! {
    loop {
        let Ok((stream, _)) = listener.accept() else {
            // Out of descriptors or an aborted handshake: the next one may do.
            thread::sleep(Duration::from_millis(50));
            continue;
        };
        let (www, wasm, hex) = (www.clone(), wasm.clone(), hex.clone());
        thread::spawn(move || {
            let _ = respond(stream, &www, &wasm, &hex);
        });
    }
}

/// Answers one request and closes the connection.
fn respond(mut stream: TcpStream, www: &Path, wasm: &Path, hex: &Path) -> std::io::Result<()> {
    stream.set_read_timeout(Some(Duration::from_secs(10)))?;
    let head = read_head(&mut stream)?;
    if let Some(query) = race_relay::query(&head) {
        let (status, body) = race_relay::answer(query);
        let header = format!(
            "HTTP/1.1 {status}\r\nContent-Type: text/plain; charset=utf-8\r\nContent-Length: {}\r\n\
             Cache-Control: no-store\r\nCross-Origin-Opener-Policy: same-origin\r\n\
             Cross-Origin-Embedder-Policy: require-corp\r\nX-Content-Type-Options: nosniff\r\n\
             Connection: close\r\n\r\n",
            body.len()
        );
        stream.write_all(header.as_bytes())?;
        stream.write_all(body.as_bytes())?;
        return stream.flush();
    }
    let takes_gzip = accepts_gzip(&head);
    let (status, content_type, body, head_only) = match request_path(&head) {
        Err(status) => (status, "text/plain; charset=utf-8", Vec::new(), false),
        Ok((path, head_only)) => {
            let file = match path.as_str() {
                WASM_URL => Some(wasm.to_path_buf()),
                HEX_URL => Some(hex.to_path_buf()),
                _ => local_file(www, &path),
            };
            // Read at every request: a rebuilt module or an edited page shows on reload.
            match file.map(|f| (std::fs::read(&f), f)) {
                Some((Ok(bytes), f)) => ("200 OK", content_type(&f), bytes, head_only),
                _ => (
                    "404 Not Found",
                    "text/plain; charset=utf-8",
                    Vec::new(),
                    head_only,
                ),
            }
        }
    };
    let body = if body.is_empty() && !status.starts_with("200") {
        format!("{status}\n").into_bytes()
    } else {
        body
    };
    let zipped = takes_gzip && status.starts_with("200") && compressible(content_type);
    let (body, encoding) = if zipped {
        (gzip(&body), "Content-Encoding: gzip\r\n")
    } else {
        (body, "")
    };
    // no-store: the page and module are rebuilt under the same names.
    // COOP/COEP make the page cross-origin isolated, which gives
    // performance.now() 5 µs resolution instead of 100 µs: the per-frame cost
    // is tens of µs. Everything is same-origin, so nothing else changes.
    let header = format!(
        "HTTP/1.1 {status}\r\nContent-Type: {content_type}\r\nContent-Length: {}\r\n\
         {encoding}Vary: Accept-Encoding\r\nCache-Control: no-store\r\nCross-Origin-Opener-Policy: same-origin\r\n\
         Cross-Origin-Embedder-Policy: require-corp\r\nX-Content-Type-Options: nosniff\r\n\
         Connection: close\r\n\r\n",
        body.len()
    );
    stream.write_all(header.as_bytes())?;
    if !head_only {
        stream.write_all(&body)?;
    }
    stream.flush()
}

/// `bytes` gzipped at the best level: a request's worth of work (the module,
/// ~150 KB, in a few ms), so the server needs no cache to keep in step with
/// rebuilds.
fn gzip(bytes: &[u8]) -> Vec<u8> {
    let mut encoder = GzEncoder::new(Vec::with_capacity(bytes.len() / 3), Compression::best());
    // Writing to a Vec cannot fail.
    let _ = encoder.write_all(bytes);
    encoder.finish().unwrap_or_default()
}

/// Whether the request's `Accept-Encoding` lists gzip (with a q-value other than 0).
fn accepts_gzip(head: &str) -> bool {
    head.lines()
        .filter_map(|line| line.split_once(':'))
        .filter(|(name, _)| name.trim().eq_ignore_ascii_case("accept-encoding"))
        .flat_map(|(_, value)| value.split(','))
        .any(|coding| {
            let mut parts = coding.split(';');
            let name = parts.next().unwrap_or_default().trim();
            let refused = parts.any(|p| {
                p.trim()
                    .strip_prefix("q=")
                    .and_then(|q| q.trim().parse::<f32>().ok())
                    == Some(0.0)
            });
            (name.eq_ignore_ascii_case("gzip") || name == "*") && !refused
        })
}

/// Whether a type is worth compressing (text and the module; images are
/// compressed already).
fn compressible(content_type: &str) -> bool {
    content_type.starts_with("text/")
        || content_type == "application/wasm"
        || content_type == "application/json"
        || content_type == "image/svg+xml"
}

/// The request line and headers, up to the blank line.
fn read_head(stream: &mut TcpStream) -> std::io::Result<String> {
    let mut head = Vec::new();
    let mut buf = [0u8; 2048];
    while !head.windows(4).any(|w| w == b"\r\n\r\n") && head.len() < MAX_HEAD {
        let n = stream.read(&mut buf)?;
        if n == 0 {
            break;
        }
        head.extend_from_slice(&buf[..n]);
    }
    Ok(String::from_utf8_lossy(&head).into_owned())
}

/// The path a GET or HEAD asks for (query dropped), and whether it is a HEAD;
/// else the error status.
fn request_path(head: &str) -> Result<(String, bool), &'static str> {
    let mut words = head.lines().next().unwrap_or_default().split_whitespace();
    let (Some(method), Some(target)) = (words.next(), words.next()) else {
        return Err("400 Bad Request");
    };
    let head_only = match method {
        "GET" => false,
        "HEAD" => true,
        _ => return Err("405 Method Not Allowed"),
    };
    let path = target.split(['?', '#']).next().unwrap_or_default();
    if !path.starts_with('/') {
        return Err("400 Bad Request");
    }
    Ok((path.to_string(), head_only))
}

/// The file under `www` for a URL path (`/` is index.html); none for a path
/// that would leave `www` or names a hidden file.
fn local_file(www: &Path, path: &str) -> Option<PathBuf> {
    let relative = match path.trim_start_matches('/') {
        "" => "index.html",
        p => p,
    };
    if relative.contains('\\') || relative.contains('%') {
        return None;
    }
    let relative = Path::new(relative);
    let plain = relative.components().all(|c| match c {
        Component::Normal(name) => !name.to_string_lossy().starts_with('.'),
        _ => false,
    });
    plain.then(|| www.join(relative))
}

/// The Content-Type for a served file, by extension: browsers compile a
/// module streamed with `application/wasm` only.
fn content_type(path: &Path) -> &'static str {
    match path.extension().and_then(|e| e.to_str()).unwrap_or("") {
        "html" => "text/html; charset=utf-8",
        "js" | "mjs" => "text/javascript; charset=utf-8",
        "css" => "text/css; charset=utf-8",
        "wasm" => "application/wasm",
        "png" => "image/png",
        "svg" => "image/svg+xml",
        "ico" => "image/x-icon",
        "json" => "application/json",
        "txt" | "level" | "hex" => "text/plain; charset=utf-8",
        _ => "application/octet-stream",
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn content_types_by_extension() {
        assert_eq!(content_type(Path::new("a/m.wasm")), "application/wasm");
        assert_eq!(
            content_type(Path::new("app.js")),
            "text/javascript; charset=utf-8"
        );
        assert_eq!(
            content_type(Path::new("index.html")),
            "text/html; charset=utf-8"
        );
        assert_eq!(
            content_type(Path::new("style.css")),
            "text/css; charset=utf-8"
        );
        assert_eq!(content_type(Path::new("web.png")), "image/png");
        assert_eq!(content_type(Path::new("x")), "application/octet-stream");
    }

    #[test]
    fn paths_stay_inside_www() {
        let www = Path::new("/w");
        assert_eq!(local_file(www, "/"), Some(PathBuf::from("/w/index.html")));
        assert_eq!(local_file(www, "/app.js"), Some(PathBuf::from("/w/app.js")));
        assert_eq!(
            local_file(www, "/js/core.js"),
            Some(PathBuf::from("/w/js/core.js"))
        );
        assert_eq!(local_file(www, "/../Cargo.toml"), None);
        assert_eq!(local_file(www, "/a/../../x"), None);
        assert_eq!(local_file(www, "/.git/config"), None);
        assert_eq!(local_file(www, "/%2e%2e/x"), None);
    }

    #[test]
    fn request_lines() {
        assert_eq!(
            request_path("GET /app.js?v=1 HTTP/1.1\r\nHost: x\r\n\r\n"),
            Ok(("/app.js".to_string(), false))
        );
        assert_eq!(
            request_path("HEAD / HTTP/1.1\r\n\r\n"),
            Ok(("/".to_string(), true))
        );
        assert_eq!(
            request_path("POST / HTTP/1.1\r\n\r\n"),
            Err("405 Method Not Allowed")
        );
        assert_eq!(request_path(""), Err("400 Bad Request"));
        assert_eq!(
            request_path("GET http://x/ HTTP/1.1"),
            Err("400 Bad Request")
        );
    }

    #[test]
    fn gzip_when_the_browser_takes_it() {
        assert!(accepts_gzip(
            "GET / HTTP/1.1\r\nAccept-Encoding: gzip, deflate, br, zstd\r\n\r\n"
        ));
        assert!(accepts_gzip(
            "GET / HTTP/1.1\r\naccept-encoding: br;q=1, GZIP;q=0.5\r\n\r\n"
        ));
        assert!(!accepts_gzip(
            "GET / HTTP/1.1\r\nAccept-Encoding: gzip;q=0\r\n\r\n"
        ));
        assert!(!accepts_gzip(
            "GET / HTTP/1.1\r\nAccept-Encoding: br\r\n\r\n"
        ));
        assert!(!accepts_gzip("GET / HTTP/1.1\r\nHost: x\r\n\r\n"));
        assert!(compressible("application/wasm") && compressible("text/html; charset=utf-8"));
        assert!(!compressible("image/png"));
        // A round trip: what the browser unpacks is the file.
        let data: Vec<u8> = (0..5000u32).map(|i| (i % 251) as u8).collect();
        let packed = gzip(&data);
        assert!(packed.len() < data.len() / 4, "{} bytes", packed.len());
        let mut unpacked = Vec::new();
        flate2::read::GzDecoder::new(&packed[..])
            .read_to_end(&mut unpacked)
            .expect("valid gzip");
        assert_eq!(unpacked, data);
    }

    #[test]
    fn finds_the_module_in_cargo_messages() {
        let line = r#"{"reason":"compiler-artifact","target":{"name":"marble_web"},"filenames":["/t/wasm32-unknown-unknown/web/marble_web.wasm"],"executable":null}"#;
        assert_eq!(
            wasm_of(line),
            Some(PathBuf::from(
                "/t/wasm32-unknown-unknown/web/marble_web.wasm"
            ))
        );
        let other = r#"{"reason":"compiler-artifact","target":{"name":"fixed"},"filenames":["/t/libfixed.rlib"]}"#;
        assert_eq!(wasm_of(other), None);
    }
}
