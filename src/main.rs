fn main() -> std::process::ExitCode {
    busnoop::cli::main()
}
