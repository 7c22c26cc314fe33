# A test that fails with MESSAGE: stands in for tests that cannot be built
# (cmake -DMESSAGE=... -P fail_with_message.cmake).
message(FATAL_ERROR "${MESSAGE}")
