fn main() -> std::process::ExitCode {
    gi_lab::cli::main()
}
