//! The `naocalib` command; all logic lives in the library (`naocalib::cli`).

fn main() -> std::process::ExitCode {
    naocalib::cli::main()
}
