!> Working precision and integer kinds shared by the whole core.
module ddpy_kinds
  use, intrinsic :: iso_c_binding, only: c_double, c_int
  implicit none
  private
  public :: wp, ip

  !> Working precision: the C double, so arrays cross the f2py layer without copies.
  integer, parameter :: wp = c_double
  !> Default integer kind at the f2py boundary.
  integer, parameter :: ip = c_int
end module ddpy_kinds
