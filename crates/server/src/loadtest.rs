//! Load test and latency benchmark (client side).
