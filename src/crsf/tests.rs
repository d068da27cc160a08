//! Decoder tests: every frame type against the public vectors' asserted values.
