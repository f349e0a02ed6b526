/// Errors of the mocap readers and writers: the shared file-error shape
/// ([`crate::util::fsutil::FileError`]). Every variant names the file and, where
/// there is one, the 1-based line the problem is on.
pub type MocapError = crate::util::fsutil::FileError;
