/// The heap counted, for the soak's memory checks (`gi_lab::heap`).
#[global_allocator]
static HEAP: gi_lab::heap::CountingAlloc = gi_lab::heap::CountingAlloc;

fn main() -> std::process::ExitCode {
    // Before any thread or GPU instance exists: a private XDG_RUNTIME_DIR when none is set,
    // so that Mesa's drivers do not complain on stderr (issue #18).
    #[cfg(target_os = "linux")]
    if !gi_lab::runtime_dir::runtime_dir_is_set()
        && let Ok(dir) = gi_lab::runtime_dir::private_runtime_dir()
    {
        // SAFETY: the process is still single-threaded here; nothing reads the environment
        // concurrently.
        unsafe { std::env::set_var("XDG_RUNTIME_DIR", dir) };
    }
    gi_lab::cli::main()
}
