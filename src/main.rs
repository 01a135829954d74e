//! The `momentlab` binary: the command line (src/cli, one file per subcommand) over the library.

mod cli;

fn main() {
    std::process::exit(cli::main());
}
