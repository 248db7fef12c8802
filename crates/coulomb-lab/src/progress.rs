//! The progress report of the engines that run time steps (`paper`): the engine says what it
//! is doing through [`Steps`], the caller decides how it is shown (the CLI: a bar on a
//! terminal, plain lines in a log; [`Hidden`]: nothing).

/// The progress report of one run of time steps, as the caller shows it.
pub trait Steps {
    /// The text before the count (the run's label).
    fn set_prefix(&self, prefix: String);
    /// The text after the count (the last step's figures).
    fn set_message(&self, message: String);
    /// `delta` more steps done.
    fn inc(&self, delta: u64);
    /// The run is over: the report is removed (or closed).
    fn finish_and_clear(&self);
}

/// Makes the progress report of a run of at most `len` steps (called on the thread that runs
/// the steps, which may be a worker of a thread pool).
pub type NewSteps<'a> = &'a (dyn Fn(usize) -> Box<dyn Steps> + Sync);

/// A progress report that shows nothing.
pub struct Hidden;

impl Steps for Hidden {
    fn set_prefix(&self, _: String) {}
    fn set_message(&self, _: String) {}
    fn inc(&self, _: u64) {}
    fn finish_and_clear(&self) {}
}
