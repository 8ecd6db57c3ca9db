"""What kingen runs on: the system C compiler, foreign code in a child process (its
household and its authenticated channel), reading given files and writing outputs and the
cache, process pools and Dask, template environments, and where the shipped resources are."""
