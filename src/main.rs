fn main() {
    std::process::exit(momentlab::cli::main());
}
