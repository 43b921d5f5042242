// Owner of the libraries' precompiled header (cmake/BuildSpeed.cmake); compiles to nothing.
