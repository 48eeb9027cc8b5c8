//! The reader process's control channel: the writer's commands, one per stdin line
//! (`report`, `start`, `stop`; stdin closing means exit), and the `seen` lines a reader
//! reports its records with. Shared by every reader mode ([`super::reader`],
//! [`super::bare`]).

use std::io::{BufRead, Write};
use std::sync::mpsc::{self, Receiver};

use super::error::Res;

/// Commands from the writer.
pub(crate) enum Cmd {
    Report,
    Start,
    Stop,
    Exit,
}

/// Reads the commands from stdin on a thread of its own; [`Cmd::Exit`] when stdin closes.
pub(crate) fn read_commands() -> Receiver<Cmd> {
    let (tx, rx) = mpsc::channel();
    std::thread::spawn(move || {
        for line in std::io::stdin().lock().lines() {
            let Ok(line) = line else { break };
            let cmd = match line.trim() {
                "report" => Cmd::Report,
                "start" => Cmd::Start,
                "stop" => Cmd::Stop,
                _ => continue,
            };
            if tx.send(cmd).is_err() {
                return;
            }
        }
        let _ = tx.send(Cmd::Exit);
    });
    rx
}

/// Prints and clears `records` as `seen` lines, then `end`.
pub(crate) fn print_records(records: &mut Vec<[u64; 3]>) -> Res<()> {
    let mut out = std::io::stdout().lock();
    for [g, t, cpu] in records.drain(..) {
        writeln!(out, "seen {g} {t} {t} {cpu}")?;
    }
    writeln!(out, "end")?;
    out.flush()?;
    Ok(())
}
