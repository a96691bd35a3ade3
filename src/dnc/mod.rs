//! Receiving NC data split into programs by start/end markers (SINUMERIK style).
