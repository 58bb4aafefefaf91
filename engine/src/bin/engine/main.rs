//! The `engine` binary: parses the command line and runs one command.

mod cli;
mod cmd;

use cli::{Cli, Command};
use engine::backend::validation;
use std::process::ExitCode;

fn main() -> ExitCode {
    let cli = Cli::parse_args();
    let (result, validate) = match &cli.command {
        None => (cmd::play::run(&cli.play), cli.play.validate),
        Some(Command::Bench(args)) => (cmd::bench::run(args), args.validate),
        Some(Command::Trace(args)) => (cmd::trace::run(args), false),
        Some(Command::Infer(args)) => (cmd::infer::run(args), args.validate),
        Some(Command::Eval(args)) => (cmd::eval::run(args), args.validate),
        Some(Command::Place(args)) => (cmd::place::run(args), args.validate),
        Some(Command::Encode(args)) => (cmd::encode::run(args), false),
        Some(Command::CodecReport(args)) => (cmd::codec_report::run(args), args.validate),
        Some(Command::Compile(args)) => (cmd::compile::run(args), args.validate),
        Some(Command::Export(args)) => (cmd::export::run(args), false),
        Some(Command::Relight(args)) => (cmd::relight::run(args), args.validate),
    };
    let mut code = ExitCode::SUCCESS;
    match result {
        Ok(text) => print!("{text}"),
        Err(e) => {
            eprintln!("error: {e:#}");
            code = ExitCode::FAILURE;
        }
    }
    if validate {
        let n = validation::message_count();
        println!("validation messages: {n}");
        if n > 0 {
            code = ExitCode::FAILURE;
        }
    }
    code
}
