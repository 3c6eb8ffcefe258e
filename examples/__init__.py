"""Examples of detectors of your own (docs/guides/your-detector.md)."""
