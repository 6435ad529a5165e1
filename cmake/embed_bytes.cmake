# What the embed_*.cmake scripts share: a file's bytes as a C initializer list, "0x7b,0x0a,...,"
# (a NUL after them is the caller's).
function(embed_bytes file out_var)
    file(READ ${file} hex HEX)
    string(REGEX REPLACE "([0-9a-f][0-9a-f])" "0x\\1," hex "${hex}")
    set(${out_var} "${hex}" PARENT_SCOPE)
endfunction()
