fn main() {
    if let Err(e) = momentlab::cli::main() {
        // One line, naming what went wrong and where (the error chain joined by ": ").
        eprintln!("error: {e:#}");
        std::process::exit(1);
    }
}
