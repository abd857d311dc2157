!> Nagata patches (triangles and quadrilaterals) built from vertices and vertex normals.
!>
!> One coefficient layout serves both shapes: S = c00 + c10 s + c01 t + c11 s t + c20 s^2
!> + c02 t^2 + c21 s^2 t + c12 s t^2, with c21 = c12 = 0 for a triangle (paper Eq. 6, 7;
!> ../docs/theory/surfaces.md). Facets are Nagata patches whose edge coefficients are all zero.
module ddpy_nagata
  use ddpy_kinds, only: wp
  implicit none
  private
  public :: nagata_edge_coefficient, nagata_patch_coefficients, nagata_evaluate, &
            nagata_coefficient_count

  !> Number of coefficient vectors per patch: c00, c10, c01, c11, c20, c02, c21, c12.
  integer, parameter :: nagata_coefficient_count = 8

contains

  !> Quadratic coefficient c of the Nagata curve C(s) = x0 + (d - c) s + c s^2 (paper Eq. 5).
  !> Degenerate-normal rule (ours, docs/theory/surfaces.md): the edge is straight when the
  !> end normals are parallel or antiparallel, or when |c| exceeds ratio_limit times the
  !> coefficient of a circular arc with the same angle phi between its end normals,
  !> |d| tan(phi/2). The second case is the blow-up of the formula, like 1/(1 - a^2), on an
  !> edge whose nearly parallel normals are not perpendicular to it (an inflexion, poor
  !> normals); a smooth edge with nearly parallel normals keeps its small curvature. Normals
  !> 120 degrees or more apart (a fold, no quadratic can follow it) give a straight edge too.
  pure function nagata_edge_coefficient(x0, x1, n0, n1, ratio_limit) result(c)
    real(wp), intent(in) :: x0(3), x1(3), n0(3), n1(3), ratio_limit
    real(wp) :: c(3)
    real(wp) :: d(3), a, d0, d1, arc
    a = dot_product(n0, n1)
    c = 0.0_wp
    if (1.0_wp - a*a <= 0.0_wp .or. a <= -0.5_wp) return
    d = x1 - x0
    d0 = dot_product(n0, d)
    d1 = dot_product(n1, d)
    c = ((d0 + a*d1)*n0 - (a*d0 + d1)*n1)/(1.0_wp - a*a)
    arc = norm2(d)*sqrt(max(1.0_wp - a, 0.0_wp)/(1.0_wp + a))
    if (norm2(c) > ratio_limit*arc) c = 0.0_wp
  end function nagata_edge_coefficient

  !> Coefficients of one patch from its corner positions x(:, 1:nv) and normals n(:, 1:nv).
  !> Triangle corners at (eta, zeta) = (0,0), (1,0), (1,1); quadrilateral corners at
  !> (xi, eta) = (0,0), (1,0), (1,1), (0,1). smooth = .false. gives the facet (all c = 0).
  pure subroutine nagata_patch_coefficients(nv, x, n, smooth, ratio_limit, coef)
    integer, intent(in) :: nv
    real(wp), intent(in) :: x(3, 4), n(3, 4), ratio_limit
    logical, intent(in) :: smooth
    real(wp), intent(out) :: coef(3, nagata_coefficient_count)
    real(wp) :: c1(3), c2(3), c3(3), c4(3)
    c1 = 0.0_wp; c2 = 0.0_wp; c3 = 0.0_wp; c4 = 0.0_wp
    coef = 0.0_wp
    if (nv == 3) then
      if (smooth) then
        c1 = nagata_edge_coefficient(x(:, 1), x(:, 2), n(:, 1), n(:, 2), ratio_limit)
        c2 = nagata_edge_coefficient(x(:, 2), x(:, 3), n(:, 2), n(:, 3), ratio_limit)
        c3 = nagata_edge_coefficient(x(:, 1), x(:, 3), n(:, 1), n(:, 3), ratio_limit)
      end if
      coef(:, 1) = x(:, 1)
      coef(:, 2) = x(:, 2) - x(:, 1) - c1
      coef(:, 3) = x(:, 3) - x(:, 2) + c1 - c3
      coef(:, 4) = c3 - c1 - c2
      coef(:, 5) = c1
      coef(:, 6) = c2
    else
      if (smooth) then
        c1 = nagata_edge_coefficient(x(:, 1), x(:, 2), n(:, 1), n(:, 2), ratio_limit)
        c2 = nagata_edge_coefficient(x(:, 2), x(:, 3), n(:, 2), n(:, 3), ratio_limit)
        c3 = nagata_edge_coefficient(x(:, 4), x(:, 3), n(:, 4), n(:, 3), ratio_limit)
        c4 = nagata_edge_coefficient(x(:, 1), x(:, 4), n(:, 1), n(:, 4), ratio_limit)
      end if
      coef(:, 1) = x(:, 1)
      coef(:, 2) = x(:, 2) - x(:, 1) - c1
      coef(:, 3) = x(:, 4) - x(:, 1) - c4
      coef(:, 4) = x(:, 3) - x(:, 2) - x(:, 4) + x(:, 1) + c1 - c2 - c3 + c4
      coef(:, 5) = c1
      coef(:, 6) = c4
      coef(:, 7) = c3 - c1
      coef(:, 8) = c2 - c4
    end if
  end subroutine nagata_patch_coefficients

  !> Point, first and second derivatives of a patch at (s, t).
  !> d1(:, 1) = S_s, d1(:, 2) = S_t; d2(:, 1) = S_ss, d2(:, 2) = S_st, d2(:, 3) = S_tt.
  pure subroutine nagata_evaluate(coef, s, t, point, d1, d2)
    real(wp), intent(in) :: coef(3, nagata_coefficient_count), s, t
    real(wp), intent(out) :: point(3), d1(3, 2), d2(3, 3)
    point = coef(:, 1) + coef(:, 2)*s + coef(:, 3)*t + coef(:, 4)*s*t + coef(:, 5)*s*s &
            + coef(:, 6)*t*t + coef(:, 7)*s*s*t + coef(:, 8)*s*t*t
    d1(:, 1) = coef(:, 2) + coef(:, 4)*t + 2.0_wp*coef(:, 5)*s + 2.0_wp*coef(:, 7)*s*t &
               + coef(:, 8)*t*t
    d1(:, 2) = coef(:, 3) + coef(:, 4)*s + 2.0_wp*coef(:, 6)*t + coef(:, 7)*s*s &
               + 2.0_wp*coef(:, 8)*s*t
    d2(:, 1) = 2.0_wp*coef(:, 5) + 2.0_wp*coef(:, 7)*t
    d2(:, 2) = coef(:, 4) + 2.0_wp*coef(:, 7)*s + 2.0_wp*coef(:, 8)*t
    d2(:, 3) = 2.0_wp*coef(:, 6) + 2.0_wp*coef(:, 8)*s
  end subroutine nagata_evaluate

end module ddpy_nagata
