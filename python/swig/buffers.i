// Typemaps that pass Python buffers of float64 (numpy arrays, array.array('d'), memoryviews) to C++
// as (pointer, length) pairs without copying. The buffer must be C-contiguous; outputs must also be
// writable. numpy.i (not shipped with SWIG) is not needed, nor are numpy's C headers.
//
//   (const double* IN_ARRAY, std::size_t IN_LENGTH)   read-only input
//   (double* OUT_ARRAY, std::size_t OUT_LENGTH)       output the C++ side fills in
//
// The C++ function checks the lengths it needs and throws if they are wrong.

%{
#include <cstddef>
#include <cstring>

namespace {

/** Holds one Python buffer of doubles for the duration of a wrapped call; released on every exit. */
class DoubleBuffer {
public:
    DoubleBuffer() : held(false) {
    }
    ~DoubleBuffer() {
        if (held)
            PyBuffer_Release(&view);
    }
    /** Get the buffer of object; on failure raise openmm.OpenMMException naming the argument. */
    bool acquire(PyObject* object, const char* name, bool writable) {
        const char* wanted = writable ? "a writable C-contiguous float64 array" : "a C-contiguous float64 array";
        int flags = PyBUF_C_CONTIGUOUS | PyBUF_FORMAT | (writable ? PyBUF_WRITABLE : 0);
        if (PyObject_GetBuffer(object, &view, flags) != 0) {
            PyErr_Clear();
            raiseOpenMMException(std::string(name) + " must be " + wanted + "; got " + Py_TYPE(object)->tp_name);
            return false;
        }
        held = true;
        if (view.itemsize != sizeof(double) || !isNativeDouble(view.format)) {
            raiseOpenMMException(std::string(name) + " must be " + wanted + "; got buffer format '" +
                                 (view.format == NULL ? "B" : view.format) + "'");
            return false;
        }
        return true;
    }
    double* data() const {
        return static_cast<double*>(view.buf);
    }
    std::size_t length() const {
        return static_cast<std::size_t>(view.len / view.itemsize);
    }
private:
    /** struct-module format of a native double: "d", optionally with a byte-order prefix that means native. */
    static bool isNativeDouble(const char* format) {
        if (format == NULL)
            return false;
        if (format[0] == '@' || format[0] == '=' || format[0] == (isLittleEndian() ? '<' : '>') ||
                (!isLittleEndian() && format[0] == '!'))
            format++;
        return std::strcmp(format, "d") == 0;
    }
    static bool isLittleEndian() {
        const unsigned int one = 1;
        unsigned char first;
        std::memcpy(&first, &one, 1);
        return first == 1;
    }
    DoubleBuffer(const DoubleBuffer&);
    DoubleBuffer& operator=(const DoubleBuffer&);
    Py_buffer view;
    bool held;
};

} // namespace
%}

%typemap(in) (const double* IN_ARRAY, std::size_t IN_LENGTH) (DoubleBuffer buffer) {
    if (!buffer.acquire($input, "$1_name", false))
        SWIG_fail;
    $1 = buffer.data();
    $2 = buffer.length();
}

%typemap(in) (double* OUT_ARRAY, std::size_t OUT_LENGTH) (DoubleBuffer buffer) {
    if (!buffer.acquire($input, "$1_name", true))
        SWIG_fail;
    $1 = buffer.data();
    $2 = buffer.length();
}
