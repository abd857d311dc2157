!> The doorway of the hexahedral solid: flat arrays and C-bound procedures that f2py wraps
!> (fortran/ddpy_core.pyf); the blank (mesh, element kind, material) is kept in the core's
!> handle table. Scalars in by value; node indices arrive 0-based and are checked and
!> converted here. Status values: 0 ok, 1 inverted element (det J0 or det F <= 0),
!> 2 material update failed, 3 node index out of range, 4 offsets inconsistent with nz,
!> 5 the solid-shell's local iteration on its enhanced parameters did not converge, 7 the
!> backstress does not fit, 8 no such blank; element is the 1-based index of the first
!> offending element (0 when none).
module ddpy_api_solid
  use, intrinsic :: iso_c_binding, only: c_int, c_double
  use ddpy_kinds, only: wp
  use ddpy_material, only: material_prop_count
  use ddpy_solid_assembly, only: solid_jacobians, solid_coo_count, solid_coo_pattern, &
                                 solid_assemble, solid_stresses, shell_modes, &
                                 kind_hexahedron, kind_solid_shell
  use ddpy_handle_table, only: table, claim_handle, valid_handle, entry_blank, &
                               refusal_index, refusal_full, refusal_value
  implicit none
  private
  public :: api_material_prop_count, api_solid_jacobians, api_solid_coo_count, &
            api_solid_coo_pattern, api_blank_create, api_solid_assemble, api_solid_stresses

  integer, parameter :: np = material_prop_count
  !> Element statuses of this doorway (the elements' own: ddpy_solid_assembly).
  integer, parameter, public :: status_bad_node = 3, status_bad_offsets = 4, &
                                status_bad_blank = 8

contains

  !> Length of the material property vector.
  subroutine api_material_prop_count(n) bind(C, name="ddpy_material_prop_count")
    integer(c_int), intent(out) :: n
    n = np
  end subroutine api_material_prop_count

  !> First element (1-based) with a node index outside 0..nn-1, or 0.
  pure integer function first_bad_element(nn, ne, conn) result(bad)
    integer, intent(in) :: nn, ne, conn(8, ne)
    integer :: e
    bad = 0
    do e = 1, ne
      if (any(conn(:, e) < 0) .or. any(conn(:, e) >= nn)) then
        bad = e
        return
      end if
    end do
  end function first_bad_element

  !> det J0 of every element at its 8 Gauss points then its 8 corners.
  subroutine api_solid_jacobians(nn, x, ne, conn, detj, status, element) &
    bind(C, name="ddpy_solid_jacobians")
    integer(c_int), value, intent(in) :: nn, ne
    real(c_double), intent(in) :: x(3, nn)
    integer(c_int), intent(in) :: conn(8, ne)
    real(c_double), intent(out) :: detj(16, ne)
    integer(c_int), intent(out) :: status, element
    detj = 0.0_wp
    status = 0
    element = first_bad_element(nn, ne, conn)
    if (element > 0) then
      status = status_bad_node
      return
    end if
    call solid_jacobians(nn, x, ne, conn + 1, detj)
  end subroutine api_solid_jacobians

  !> Coordinate entries per element for the equation numbers eqn (0-based, -1 constrained).
  subroutine api_solid_coo_count(nn, ne, conn, eqn, symmetric, counts, status, element) &
    bind(C, name="ddpy_solid_coo_count")
    integer(c_int), value, intent(in) :: nn, ne, symmetric
    integer(c_int), intent(in) :: conn(8, ne), eqn(3, nn)
    integer(c_int), intent(out) :: counts(ne), status, element
    counts = 0
    status = 0
    element = first_bad_element(nn, ne, conn)
    if (element > 0) then
      status = status_bad_node
      return
    end if
    call solid_coo_count(nn, ne, conn + 1, eqn, symmetric /= 0, counts)
  end subroutine api_solid_coo_count

  !> 0-based rows and columns of all slots; offsets(e) is the first slot of element e minus 1
  !> (0-based start), offsets(ne + 1) = nz.
  subroutine api_solid_coo_pattern(nn, ne, conn, eqn, symmetric, offsets, nz, rows, cols, &
                                   status, element) bind(C, name="ddpy_solid_coo_pattern")
    integer(c_int), value, intent(in) :: nn, ne, symmetric, nz
    integer(c_int), intent(in) :: conn(8, ne), eqn(3, nn), offsets(ne + 1)
    integer(c_int), intent(out) :: rows(nz), cols(nz), status, element
    rows = 0
    cols = 0
    status = 0
    element = first_bad_element(nn, ne, conn)
    if (element > 0) then
      status = status_bad_node
      return
    end if
    if (offsets(ne + 1) /= nz) then
      status = status_bad_offsets
      return
    end if
    call solid_coo_pattern(nn, ne, conn + 1, eqn, symmetric /= 0, offsets, nz, rows, cols)
  end subroutine api_solid_coo_pattern

  !> A blank in the core's handle table (ddpy_blank): nn nodes x, ne elements conn
  !> (0-based) of the given kind (0 hexahedron, 1 solid-shell) and the material props.
  !> status: 0, or a refusal of ddpy_handle_table (refusal_index with the first element,
  !> 1-based, whose node is out of range; refusal_value an unknown kind).
  subroutine api_blank_create(nn, x, ne, conn, kind, props, handle, status, element) &
    bind(C, name="ddpy_blank_create")
    integer(c_int), value, intent(in) :: nn, ne, kind
    real(c_double), intent(in) :: x(3, nn), props(np)
    integer(c_int), intent(in) :: conn(8, ne)
    integer(c_int), intent(out) :: handle, status, element
    handle = 0
    status = refusal_value
    element = 0
    if (kind /= kind_hexahedron .and. kind /= kind_solid_shell) return
    status = refusal_index
    element = first_bad_element(nn, ne, conn)
    if (element > 0) return
    status = refusal_full
    call claim_handle(entry_blank, handle)
    if (handle == 0) return
    allocate(table(handle)%blank)
    associate (b => table(handle)%blank)
      b%nnode = nn
      b%ne = ne
      b%kind = kind
      b%x0 = x
      b%conn = conn + 1
      b%props = props
    end associate
    status = 0
  end subroutine api_blank_create

  !> Internal forces, tangent values in the slots of solid_coo_pattern (when tangent /= 0)
  !> and the trial material state of the blank behind handle blank at total displacements
  !> u, over the increment from the converged state at displacements u_ref (the solid-
  !> shell's enhanced parameters start at alpha_in and end at alpha); with product /= 0
  !> also kdu = K dp (K over all dofs, dp the increment of prescribed displacements).
  !> back_old, back (6, 8, nback): the backstress of mixed hardening (nback = ne), else not
  !> read (any nback; f2py passes one element's worth). status_bad_blank where the handle
  !> holds no blank of nn nodes and ne elements.
  subroutine api_solid_assemble(blank, nn, u_ref, u, ne, axes_old, stress_old, ep_old, &
                                strain_old, nback, back_old, alpha_in, eqn, symmetric, &
                                tangent, offsets, nz, values, product, dp, fint, kdu, stress, &
                                ep, strain, axes, back, alpha, status, element) &
    bind(C, name="ddpy_solid_assemble")
    integer(c_int), value, intent(in) :: blank, nn, ne, symmetric, tangent, nz, product, &
                                         nback
    real(c_double), intent(in) :: u_ref(3, nn), u(3, nn), dp(3, nn)
    integer(c_int), intent(in) :: eqn(3, nn), offsets(ne + 1)
    real(c_double), intent(in) :: axes_old(3, 3, 8, ne), stress_old(6, 8, ne), &
                                  ep_old(8, ne), strain_old(6, 8, ne), &
                                  back_old(6, 8, nback), alpha_in(shell_modes, ne)
    real(c_double), intent(inout) :: values(nz), back(6, 8, nback)
    real(c_double), intent(out) :: fint(3, nn), kdu(3, nn), stress(6, 8, ne), ep(8, ne), &
                                   strain(6, 8, ne), axes(3, 3, 8, ne), &
                                   alpha(shell_modes, ne)
    integer(c_int), intent(out) :: status, element
    fint = 0.0_wp
    kdu = 0.0_wp
    alpha = alpha_in
    status = status_bad_blank
    element = 0
    if (.not. valid_handle(blank, entry_blank)) return
    if (table(blank)%blank%nnode /= nn .or. table(blank)%blank%ne /= ne) return
    status = 0
    if (tangent /= 0 .and. offsets(ne + 1) /= nz) then
      status = status_bad_offsets
      return
    end if
    associate (b => table(blank)%blank)
      call solid_assemble(nn, b%x0, ne, b%conn, b%kind, u_ref, u, b%props, axes_old, &
                          stress_old, ep_old, strain_old, nback, back_old, alpha_in, eqn, &
                          symmetric /= 0, tangent /= 0, offsets, nz, values, product /= 0, dp, &
                          fint, kdu, stress, ep, strain, axes, back, alpha, status, element)
    end associate
  end subroutine api_solid_assemble

  !> Second Piola-Kirchhoff (global axes), Cauchy stresses and current Gauss point positions
  !> from the state's material axes and rotated Kirchhoff stresses.
  subroutine api_solid_stresses(nn, x, ne, conn, u, axes, stress_mat, pk2, cauchy, points, &
                                status, element) bind(C, name="ddpy_solid_stresses")
    integer(c_int), value, intent(in) :: nn, ne
    real(c_double), intent(in) :: x(3, nn), u(3, nn), axes(3, 3, 8, ne), stress_mat(6, 8, ne)
    integer(c_int), intent(in) :: conn(8, ne)
    real(c_double), intent(out) :: pk2(6, 8, ne), cauchy(6, 8, ne), points(3, 8, ne)
    integer(c_int), intent(out) :: status, element
    pk2 = 0.0_wp
    cauchy = 0.0_wp
    points = 0.0_wp
    status = 0
    element = first_bad_element(nn, ne, conn)
    if (element > 0) then
      status = status_bad_node
      return
    end if
    call solid_stresses(nn, x, ne, conn + 1, u, axes, stress_mat, pk2, cauchy, points, &
                        status, element)
  end subroutine api_solid_stresses

end module ddpy_api_solid
