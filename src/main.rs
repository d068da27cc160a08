fn main() -> std::process::ExitCode {
    busnoop::main()
}

/// Runs before `main`, and before the Rust runtime's start-up, which puts /dev/null on a closed
/// standard output (`>&-`): busnoop refuses to write its table where it would vanish, and only
/// here can a closed descriptor be told from an open /dev/null.
extern "C" fn look_at_stdout() {
    busnoop::note_stdout_at_start();
}

#[cfg(any(
    target_os = "linux",
    target_os = "android",
    target_os = "freebsd",
    target_os = "netbsd",
    target_os = "openbsd",
    target_os = "dragonfly",
    target_os = "illumos",
    target_os = "solaris"
))]
#[used]
#[unsafe(link_section = ".init_array")]
static LOOK_AT_STDOUT: extern "C" fn() = look_at_stdout;

#[cfg(target_vendor = "apple")]
#[used]
#[unsafe(link_section = "__DATA,__mod_init_func")]
static LOOK_AT_STDOUT: extern "C" fn() = look_at_stdout;
