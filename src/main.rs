fn main() -> std::process::ExitCode {
    busnoop::main()
}
