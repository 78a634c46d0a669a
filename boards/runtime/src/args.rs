//! The benchmarks' options on the semihosting command line: `--name=N`, a
//! number (a mask of backends, rates, scenes). The Cortex-M4F benchmark
//! (`marble-qemu`'s `bench`) and the Cortex-M0 one (`marble-bench-m0`) read
//! the same options the same way, so they are read here once.

/// The number `N` of the first `name=N` argument on the command line, or
/// `default` when there is none, it is not a number, or the command line cannot
/// be read (a run outside QEMU's semihosting).
pub fn number_option(name: &str, default: u32) -> u32 {
    let Ok(args) = semihosting::experimental::env::args::<256>() else {
        return default;
    };
    for arg in (&args).filter_map(Result::ok) {
        if let Some(v) = arg.strip_prefix(name).and_then(|v| v.strip_prefix('=')) {
            if let Ok(m) = v.parse::<u32>() {
                return m;
            }
        }
    }
    default
}
