//! The `naocalib` command: flag parsing and printing only; everything else is the library.

mod cli;

fn main() -> std::process::ExitCode {
    cli::main()
}
