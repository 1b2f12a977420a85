// What every route needs: JSON, error and image responses, a finished job's result with its
// caching headers, the query parameters read the same way everywhere, and who is asking.
#pragma once

#include <httplib.h>

#include <initializer_list>
#include <optional>
#include <string>
#include <string_view>

#include <nlohmann/json.hpp>

#include "job_record.h"
#include "service.h"

namespace rayfarm::server {

// Set on a request that came form-encoded (what curl -d and --data-binary send).
inline constexpr const char* kFormEncodedMark = "X-Rayfarm-Form-Encoded";
// Who asked, by roster name ("name:alice"), as the server found it from the token.
inline constexpr const char* kClientHeader = "X-Rayfarm-Client";

void send_json(httplib::Response& res, int status, const nlohmann::json& body);
void send_error(httplib::Response& res, const ApiError& e);
void send_error(httplib::Response& res, int status, const std::string& code,
                const std::string& message);
void send_image(httplib::Response& res, const Image& image, bool ppm);
// ASCII letters in lower case (header values that are case-insensitive), and a value without
// the spaces and tabs around it.
std::string lower_ascii(std::string_view s);
std::string_view trim(std::string_view s);
// A request target in absolute form ("http://host:8080/jobs?x=1", which a server must accept:
// RFC 9112 §3.2.2) as the origin form the routes match ("/jobs?x=1"); any other unchanged.
std::string origin_form(std::string_view target);

// Whether a GET or HEAD request's If-None-Match names `etag` (RFC 9110 §13.1.2): a list of
// tags, weak or strong (compared weakly), or "*" for any current representation.
bool none_match_hits(const httplib::Request& req, std::string_view etag);
// Sends a finished job's result with its caching headers; false when it has expired.
bool send_result(Service& service, const httplib::Request& req, httplib::Response& res,
                 const JobRecord& job);

// A query parameter a route takes, and the values it takes (none listed: any).
struct QueryParam {
  std::string_view name;
  std::initializer_list<std::string_view> values = {};
};
// Refuses (400 invalid_option, with the nearest name or the values taken) a query parameter
// the route does not take, a value it does not know, or one given twice: a typo never passes
// silently. False when it has answered.
bool check_query(const httplib::Request& req, httplib::Response& res, std::string_view route,
                 std::initializer_list<QueryParam> taken);

// ?format=ppm, else the format the job was submitted with.
bool wants_ppm(const httplib::Request& req, const JobRecord& job);

// The answer for a failed job's result (its image, or a wait=1 render): a render that could
// not start was refused for what it asked; a crash or a lost job is the server's.
ApiError failed_job_error(const JobRecord& job);
// The yes/no words of every option: 1, true, yes; 0, false, no. Anything else: nullopt.
std::optional<bool> yes_no(std::string_view word);
// The 400 invalid_option for a yes/no option `name` given `value`, which is not such a word.
ApiError not_yes_no(const std::string& name, const std::string& value);
// ?NAME=1, true or yes.
bool param_true(const httplib::Request& req, const char* name);
// A query piece with two '=' (`spp=2=3`, or `seed=1;spp=9`: ';' separates nothing): cpp-httplib
// keeps what follows the last one, a value the client never sent; or a name given twice. A
// 400 invalid_option to answer, or none.
ApiError ambiguous_query(std::string_view target);
// A yes/no query option: 1, true, yes, 0, false or no when given; anything else (wait=2) is
// answered 400 invalid_option here, and false returned.
bool check_yes_no(const httplib::Request& req, httplib::Response& res, const char* name);

// The parts of a multipart request that are not the route's own (`own`): texture files, by
// the path the scene names them with. A name sent twice is a 400 (which file was meant?).
ApiError texture_parts(const httplib::Request& req, std::initializer_list<std::string_view> own,
                       TextureFiles& out);

// The token of an `Authorization: Bearer` header; empty when there is none.
std::string bearer_token(const httplib::Request& req);
// Who is asking: the roster's name for the token, else the token's digest, else the
// socket's address (never a header the client set).
std::string client_of(const httplib::Request& req);

}  // namespace rayfarm::server
