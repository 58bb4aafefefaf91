use clap::Parser;
use engine::backend::validation;
use engine::cli::Cli;
use std::process::ExitCode;

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = engine::play::play(&cli.play);
    let mut code = ExitCode::SUCCESS;
    match result {
        Ok(report) => print!("{}", report.table()),
        Err(e) => {
            eprintln!("error: {e:#}");
            code = ExitCode::FAILURE;
        }
    }
    if cli.play.validate {
        let n = validation::message_count();
        println!("validation messages: {n}");
        if n > 0 {
            code = ExitCode::FAILURE;
        }
    }
    code
}
