//! On SIGINT or SIGTERM the CLI removes what the interrupted command half-made: the output
//! directories it created and every temporary file being written
//! ([`refract_lab::output_dirs::remove_created`]).

/// On SIGINT or SIGTERM: remove what is half-made, say so, exit 130.
pub fn install_signal_handler() {
    let installed = ctrlc::set_handler(|| {
        refract_lab::output_dirs::interrupt();
        eprintln!("interrupted: removed partial output");
        std::process::exit(130);
    });
    if let Err(err) = installed {
        eprintln!("warning: cannot install the interrupt handler: {err}");
    }
}

/// When the run was interrupted, the handler's thread owns the exit (status 130, after it has
/// removed the partial output): the main thread waits for it instead of exiting with its own
/// status. Without this, a command that failed because the handler had just removed its
/// output directory could exit 1 before the handler exited 130.
pub fn yield_to_interrupt() {
    if refract_lab::output_dirs::interrupted() {
        loop {
            std::thread::park();
        }
    }
}
