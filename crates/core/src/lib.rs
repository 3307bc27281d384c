//! GPLVM core
