"""FMUs: model description, builders per runtime, runtime template, C sources."""
