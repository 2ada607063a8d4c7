//! On SIGINT or SIGTERM the CLI removes what the interrupted command half-made: the output
//! directories it created and every temporary file being written
//! ([`refract_lab::output_dirs::remove_created`]).

/// On SIGINT or SIGTERM: remove what is half-made, say so, exit 130.
pub fn install_signal_handler() {
    let installed = ctrlc::set_handler(|| {
        refract_lab::output_dirs::remove_created();
        eprintln!("interrupted: removed partial output");
        std::process::exit(130);
    });
    if let Err(err) = installed {
        eprintln!("warning: cannot install the interrupt handler: {err}");
    }
}
