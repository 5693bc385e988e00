/* How to read render_options.def, the table of render options: each user defines TPK_OPTION (and the
 * group macros TPK_RULE, TPK_CLI, TPK_KEY, TPK_USE it needs) to pick the columns it wants, includes the
 * .def, and undefines them. TPK_IF keeps what a row's R, A or S column (0 or 1) asks for. */
#ifndef TPK_RENDER_OPTIONS_H
#define TPK_RENDER_OPTIONS_H

#define TPK_IF(flag, ...) TPK_IF_##flag(__VA_ARGS__)
#define TPK_IF_0(...)
#define TPK_IF_1(...) __VA_ARGS__

/* The C type of a field of each KIND. */
#define TPK_OPTION_CTYPE_OTHER int
#define TPK_OPTION_CTYPE_INT int
#define TPK_OPTION_CTYPE_NUMBER double
#define TPK_OPTION_CTYPE_CHOICE int
#define TPK_OPTION_CTYPE_BOOL int

/* 1 where a KIND's field is a double. */
#define TPK_OPTION_REAL_OTHER 0
#define TPK_OPTION_REAL_INT 0
#define TPK_OPTION_REAL_NUMBER 1
#define TPK_OPTION_REAL_CHOICE 0
#define TPK_OPTION_REAL_BOOL 0

/* The halves of the vertex cache (render.h OCCLUSION AT VERTICES) an option's value is an input of. */
#define TPK_OPTION_CACHE_NONE 0
#define TPK_OPTION_CACHE_S 1
#define TPK_OPTION_CACHE_A 2
#define TPK_OPTION_CACHE_BOTH 3

/* The declarations of the fields of the rows whose column `where` (R, A or S) is 1, for a struct. */
#define TPK_OPTION_FIELD_R(ID, name, kind, R, A, S, ...) TPK_IF(R, TPK_OPTION_CTYPE_##kind name;)
#define TPK_OPTION_FIELD_A(ID, name, kind, R, A, S, ...) TPK_IF(A, TPK_OPTION_CTYPE_##kind name;)
#define TPK_OPTION_FIELD_S(ID, name, kind, R, A, S, ...) TPK_IF(S, TPK_OPTION_CTYPE_##kind name;)

#endif
