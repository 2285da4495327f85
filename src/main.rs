//! The `fitup` binary: see [`fitup::cli`].

fn main() {
    std::process::exit(fitup::cli::main());
}
