// Signatures that inspect.signature can read, for every function of the
// module.
//
// pybind11 2.10 starts each function's docstring with its signature, with
// types: "insert(self: umbra._umbra.OccupancyMap, points: object, ...) ->
// umbra._umbra.InsertStats". help() shows that line, but inspect.signature
// raises ValueError: CPython reads the signature of a built-in function
// from __text_signature__, which is the first line of the C-level docstring
// when it reads "name(arguments)\n--\n\n" in Python syntax without
// annotations (Argument Clinic's convention). So after all bindings are made
// this pass puts such a line, computed from pybind11's own, in front of each
// docstring; __doc__ stays what it was (CPython hides the line). Where
// inspect still cannot read it (a default value that is not a literal) the
// line is taken out again and inspect.signature raises as before.
//
// The C-level docstring belongs to pybind11's function record: pybind11
// allocates it with strdup and frees it with free (pybind11.h,
// cpp_function::initialize_generic and destruct), and so does this file.
// Only functions pybind11 made (their __self__ is its capsule) are touched.
#include <cstdlib>
#include <cstring>
#include <string>
#include <string_view>
#include <vector>

#include "bindings.hpp"

namespace umbra::python {
namespace {

/// The parameters of a pybind11 signature "(a: T = 1, *, b: U)" without
/// annotations: "a=1, *, b". Empty when the text is not such a signature.
std::string parameters_without_annotations(std::string_view signature) {
  // Split at the commas outside brackets and quotes.
  std::vector<std::string_view> parameters;
  int depth = 0;
  char quote = 0;
  std::size_t start = 0;
  for (std::size_t i = 0; i < signature.size(); ++i) {
    const char c = signature[i];
    if (quote) {
      if (c == '\\') ++i;
      else if (c == quote) quote = 0;
    } else if (c == '\'' || c == '"') {
      quote = c;
    } else if (c == '(' || c == '[' || c == '{' || c == '<') {
      ++depth;
    } else if (c == ')' || c == ']' || c == '}' || c == '>') {
      --depth;
    } else if (c == ',' && depth == 0) {
      parameters.push_back(signature.substr(start, i - start));
      start = i + 1;
    }
  }
  if (!signature.empty()) parameters.push_back(signature.substr(start));

  std::string text;
  for (std::string_view parameter : parameters) {
    while (!parameter.empty() && parameter.front() == ' ') parameter.remove_prefix(1);
    const std::size_t colon = parameter.find(':');
    const std::size_t equals = parameter.find(" = ");
    const std::string_view name = parameter.substr(0, std::min(colon, equals));
    if (!text.empty()) text += ", ";
    text += name;
    if (equals != std::string_view::npos) {
      // inspect reads literals only; pybind11 writes an infinite default as
      // repr() does, "inf", which is a name. 1e309 is the same float.
      std::string_view value = parameter.substr(equals + 3);
      text += '=';
      if (value == "inf" || value == "-inf") {
        text += value.front() == '-' ? "-1e309" : "1e309";
      } else {
        text += value;
      }
    }
  }
  return text;
}

/// "name(a=1, *, b)" from the first line of pybind11's docstring
/// "name(a: T = 1, *, b: U) -> R", or "" when it does not start with name(.
std::string text_signature(std::string_view name, std::string_view doc) {
  if (doc.substr(0, name.size()) != name || doc.size() <= name.size() || doc[name.size()] != '(') return "";
  // The closing parenthesis of the parameter list: brackets in types and
  // quoted defaults ("')'") are skipped.
  int depth = 0;
  char quote = 0;
  for (std::size_t i = name.size(); i < doc.size(); ++i) {
    const char c = doc[i];
    if (c == '\n') return "";
    if (quote) {
      if (c == '\\') ++i;
      else if (c == quote) quote = 0;
    } else if (c == '\'' || c == '"') {
      quote = c;
    } else if (c == '(' || c == '[') {
      ++depth;
    } else if ((c == ')' || c == ']') && --depth == 0) {
      const std::size_t open = name.size() + 1;
      return std::string(name) + "(" + parameters_without_annotations(doc.substr(open, i - open)) + ")";
    }
  }
  return "";
}

/// The text signature of a function: of its one signature, or of its
/// overloads ("name(*args, **kwargs)\nOverloaded function.\n\n1. name(a:
/// Aabb)...\n\n2. name(a: Sphere)...") when they differ only in types, as
/// the shape overloads of is_free do; "" when they differ otherwise.
std::string function_text_signature(std::string_view name, std::string_view doc) {
  const std::string overloaded = std::string(name) + "(*args, **kwargs)\nOverloaded function.";
  if (doc.substr(0, overloaded.size()) != overloaded) return text_signature(name, doc);
  std::string common;
  std::size_t line_start = 0;
  while (line_start < doc.size()) {
    const std::size_t line_end = std::min(doc.find('\n', line_start), doc.size());
    const std::string_view line = doc.substr(line_start, line_end - line_start);
    const std::size_t dot = line.find(". ");
    if (dot != std::string_view::npos && dot > 0 &&
        line.substr(0, dot).find_first_not_of("0123456789") == std::string_view::npos) {
      const std::string signature = text_signature(name, line.substr(dot + 2));
      if (signature.empty() || (!common.empty() && signature != common)) return "";
      common = signature;
    }
    line_start = line_end + 1;
  }
  return common;
}

/// Replaces the C-level docstring of a pybind11 function (see the top).
void set_internal_doc(PyCFunctionObject* function, const std::string& doc) {
  char* copy = strdup(doc.c_str());
  if (copy == nullptr) throw std::bad_alloc();
  std::free(const_cast<char*>(function->m_ml->ml_doc));
  function->m_ml->ml_doc = copy;
}

void add_text_signature(py::handle object, const py::object& signature_of) {
  if (!PyCFunction_Check(object.ptr()) || !PyCapsule_CheckExact(PyCFunction_GET_SELF(object.ptr()))) return;
  auto* function = reinterpret_cast<PyCFunctionObject*>(object.ptr());
  const char* old_doc = function->m_ml->ml_doc;
  if (old_doc == nullptr) return;
  const std::string doc(old_doc);
  const std::string line = function_text_signature(function->m_ml->ml_name, doc);
  if (line.empty()) return;
  set_internal_doc(function, line + "\n--\n\n" + doc);
  try {
    signature_of(object);
  } catch (const py::error_already_set&) {
    set_internal_doc(function, doc);  // not a signature inspect reads: as pybind11 wrote it
  }
}

void add_text_signatures_to_class(py::handle type, const py::object& signature_of) {
  // The class's own dict (type.__dict__ is a read-only proxy of it).
  const auto members = py::reinterpret_borrow<py::dict>(reinterpret_cast<PyTypeObject*>(type.ptr())->tp_dict);
  for (const auto item : members) {
    py::handle member = item.second;
    if (PyInstanceMethod_Check(member.ptr())) {
      add_text_signature(PyInstanceMethod_Function(member.ptr()), signature_of);
    } else if (PyObject_TypeCheck(member.ptr(), &PyStaticMethod_Type)) {
      add_text_signature(member.attr("__func__"), signature_of);
    } else {
      add_text_signature(member, signature_of);
    }
  }
  // inspect.signature(Class) passes over a built-in __init__ but reads a
  // __signature__ attribute: that of __init__ without self.
  if (!members.contains("__init__") || !PyInstanceMethod_Check(members["__init__"].ptr())) return;
  try {
    const py::object init = signature_of(py::handle(PyInstanceMethod_Function(members["__init__"].ptr())));
    const py::list parameters(init.attr("parameters").attr("values")());
    py::list without_self;
    for (std::size_t i = 1; i < parameters.size(); ++i) without_self.append(parameters[i]);
    type.attr("__signature__") = init.attr("replace")(py::arg("parameters") = without_self);
  } catch (const py::error_already_set&) {
    // __init__ has no signature inspect reads: neither has the class.
  }
}

}  // namespace

void add_text_signatures(py::module_& m) {
  const py::object signature_of = py::module_::import("inspect").attr("signature");
  for (const auto item : m.attr("__dict__").cast<py::dict>()) {
    py::handle value = item.second;
    if (py::isinstance<py::module_>(value)) {
      // umbra.pred and umbra.sim (def_submodule), not modules imported elsewhere.
      auto submodule = py::reinterpret_borrow<py::module_>(value);
      const auto name = submodule.attr("__name__").cast<std::string>();
      if (name.rfind(m.attr("__name__").cast<std::string>() + ".", 0) == 0) add_text_signatures(submodule);
    } else if (PyType_Check(value.ptr())) {
      add_text_signatures_to_class(value, signature_of);
    } else {
      add_text_signature(value, signature_of);
    }
  }
}

}  // namespace umbra::python
