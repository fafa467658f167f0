"""The machinery the subcommands share: executors, campaigns, output folders, scene sources and tables."""
