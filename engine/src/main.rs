use clap::Parser;
use engine::backend::validation;
use engine::cli::{Cli, Command};
use std::process::ExitCode;

fn main() -> ExitCode {
    let cli = Cli::parse();
    let (result, validate) = match &cli.command {
        None => (
            engine::play::play(&cli.play).map(|r| r.table()),
            cli.play.validate,
        ),
        Some(Command::Bench(args)) => {
            (engine::bench::bench(args).map(|r| r.table()), args.validate)
        }
        Some(Command::Trace(args)) => (engine::trace_cmd::trace(args), false),
        Some(Command::Infer(args)) => (engine::infer_cmd::infer(args), args.validate),
        Some(Command::Eval(args)) => (engine::eval_cmd::eval(args), args.validate),
        Some(Command::Encode(args)) => (engine::codec_cmd::encode(args), false),
        Some(Command::CodecReport(args)) => (engine::codec_cmd::codec_report(args), false),
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
