//! The build script of every firmware crate (`build = "../runtime/build.rs"`
//! in each one's Cargo.toml): links with that crate's own `memory.x` (cargo
//! runs a build script in its package's directory, `CARGO_MANIFEST_DIR`),
//! included by cortex-m-rt's `link.x` from the linker's search path. (There is
//! no `memory.x` at the workspace root on purpose: the linker runs there and
//! would take that one first.)
fn main() {
    let dir = std::env::var("CARGO_MANIFEST_DIR").unwrap_or_default();
    println!("cargo:rustc-link-search={dir}");
    println!("cargo:rerun-if-changed=memory.x");
    println!("cargo:rustc-link-arg-bins=--nmagic");
    println!("cargo:rustc-link-arg-bins=-Tlink.x");
    println!("cargo:rustc-link-arg-bins=-Tdefmt.x");
}
