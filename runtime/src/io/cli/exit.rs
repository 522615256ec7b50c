//! A failure as the command line reports it: the message (and a JSON
//! line under `--summary json`), and its exit status.

use crate::failure::Failure;
use crate::io::summary::json_string;
use std::process::ExitCode;

pub(crate) fn fail(json: bool, failure: &Failure) -> ExitCode {
    let message = failure.to_string();
    if json {
        eprintln!("{{\"failed\":true,\"message\":{}}}", json_string(&message));
    }
    eprintln!("error: {message}");
    ExitCode::from(failure.exit_status())
}
